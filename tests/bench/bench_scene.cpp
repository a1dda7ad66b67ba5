// Cost of finding the objects of a depth camera's frame (segment_scene: voxel grid, planes by RANSAC,
// Euclidean clusters): a real Kinect-class desk frame (640 x 480, ~270k points with depth; skipped when
// ../shared/data/real-scenes is absent) and a synthetic 640 x 480 room of four objects. Median of five.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "../core/synthetic_scene.h"
#include "glimpse/geometry/scene.h"
#include "glimpse/io/files.h"

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

}  // namespace

BENCHMARK_MAIN();
