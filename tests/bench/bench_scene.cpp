// Cost of finding the objects of a depth camera's frame (segment_scene: voxel grid, planes by RANSAC,
// Euclidean clusters): a real Kinect-class desk frame (640 x 480, ~270k points with depth; skipped when
// ../shared/data/real-scenes is absent) and a synthetic 640 x 480 room of four objects. Then what
// ClassifyScene does with a 640 x 480 room of five objects: segment it and classify every object, one
// thread per object as the server does (the same frame segmented alone is the baseline). The model is the
// zoo's recipe model (5 objects a category), or the serialized model GLIMPSE_BENCH_MODEL names (e.g. a
// stored SHREC recipe model). Median of five.
#include <benchmark/benchmark.h>

#include <omp.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "../core/synthetic_scene.h"
#include "glimpse/geometry/scene.h"
#include "glimpse/io/files.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "zoo_recipe.h"

namespace {

using namespace glimpse;

void segment(benchmark::State& state, const Cloud& frame) {
  size_t objects = 0, planes = 0;
  for (auto _ : state) {
    Expected<Scene> scene = segment_scene(frame);
    if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
    objects = scene->objects.size();
    planes = scene->planes.size();
  }
  state.counters["points"] = double(frame.points.size());
  state.counters["planes"] = double(planes);
  state.counters["objects"] = double(objects);
}

void BM_SegmentDeskFrame(benchmark::State& state) {
  const char* env = std::getenv("GLIMPSE_REAL_SCENES_DIR");
  const std::string dir = env ? env : GLIMPSE_SOURCE_DIR "/../shared/data/real-scenes";
  static const Expected<Cloud> frame = read_cloud(dir + "/desk_laptop_box_frame0.pcd");
  if (!frame.ok()) return state.SkipWithError(("no desk frame: " + frame.error().message).c_str());
  segment(state, *frame);
}
BENCHMARK(BM_SegmentDeskFrame)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

void BM_SegmentSyntheticRoom(benchmark::State& state) {
  static const Cloud frame = test::four_object_scene().frame;
  segment(state, frame);
}
BENCHMARK(BM_SegmentSyntheticRoom)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

// Five objects, 30 cm to 1 m across, standing apart on the floor 1.8-3 m from the camera.
const Cloud& five_object_frame() {
  using test::SceneShape;
  static const Cloud frame = test::render_scene(
      test::Room{},
      {{SceneShape::kBox, Vec3(-0.9f, 2.0f, 0), Vec3(0.5f, 0.4f, 0.75f)},
       {SceneShape::kCylinder, Vec3(-0.25f, 2.6f, 0), Vec3(0.15f, 0, 0.9f)},
       {SceneShape::kSphere, Vec3(0.35f, 1.9f, 0), Vec3(0.2f, 0, 0)},
       {SceneShape::kBox, Vec3(0.95f, 2.7f, 0), Vec3(1.0f, 0.6f, 0.7f)},
       {SceneShape::kCylinder, Vec3(0.2f, 3.2f, 0), Vec3(0.25f, 0, 0.45f)}},
      Vec3(0, 0, 1.3f), Vec3(0, 2.5f, 0.3f)).frame;
  return frame;
}

const Model* scene_model() {
  static const std::unique_ptr<Model> model = []() -> std::unique_ptr<Model> {
    if (const char* path = std::getenv("GLIMPSE_BENCH_MODEL")) {
      std::ifstream in(path, std::ios::binary);
      const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      auto read = deserialize(bytes);
      return read.ok() ? std::make_unique<Model>(std::move(*read)) : nullptr;
    }
    auto trained = train(bench::zoo_training_set(5), TrainParams{});
    return trained.ok() ? std::make_unique<Model>(std::move(*trained)) : nullptr;
  }();
  return model.get();
}

void BM_SegmentFiveObjectRoom(benchmark::State& state) { segment(state, five_object_frame()); }
BENCHMARK(BM_SegmentFiveObjectRoom)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

void BM_SegmentAndClassifyFiveObjectRoom(benchmark::State& state) {
  const Model* model = scene_model();
  if (!model) return state.SkipWithError("no model: training failed or GLIMPSE_BENCH_MODEL unreadable");
  const Cloud& frame = five_object_frame();
  size_t objects = 0, classified = 0;
  for (auto _ : state) {
    Expected<Scene> scene = segment_scene(frame);
    if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
    objects = scene->objects.size();
    std::vector<int> ok(objects, 0);
    const int threads = std::max(1, std::min(omp_get_max_threads(), int(objects)));
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int64_t i = 0; i < int64_t(objects); ++i) {
      omp_set_num_threads(1);
      ok[size_t(i)] = classify(*model, object_cloud(frame, scene->objects[size_t(i)])).ok();
    }
    classified = size_t(std::count(ok.begin(), ok.end(), 1));
  }
  state.counters["objects"] = double(objects);
  state.counters["classified"] = double(classified);
  state.counters["threads"] = double(omp_get_max_threads());
}
BENCHMARK(BM_SegmentAndClassifyFiveObjectRoom)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
