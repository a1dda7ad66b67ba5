// Cost of the simulated sensors' ray casting: a depth camera (640 x 480 rays) looking at a zoo chair
// from 1.5 m, 15 deg up, as the training views are made, without and with the floor patch; the camera
// casts only the pixels whose rays can reach the scene, against every pixel in the same process. The
// camera casts each row as packets of 8 (RayScene::cast_many); the baseline in the same process casts the
// same pixels one ray at a time (RayScene::cast). Both find the same hits.
#include <benchmark/benchmark.h>

#include <chrono>

#include "glimpse/geometry/scan_filters.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/views/scan_conditions.h"
#include "glimpse/views/sensors.h"
#include "glimpse/views/zoo.h"

namespace {

using namespace glimpse;

const RayScene& chair_scene(bool floor) {
  static const Mesh mesh = *make_zoo_shape("chair", 1);
  static const RayScene bare = *RayScene::build(mesh), floored = *RayScene::build(mesh, 1.5f);
  return floor ? floored : bare;
}

SensorPose camera_pose() {
  static const Mesh mesh = *make_zoo_shape("chair", 1);
  return orbit_pose(bounds(mesh.vertices).centre(), 30.f, 15.f, 1.5f);
}

// The camera's pixel rays, row after row, and their reach (max range along each ray).
struct Frame {
  Vec3 origin;
  std::vector<Vec3> rays;
  std::vector<float> reach;
};
Frame camera_frame() {
  const DepthCameraParams p;
  const SensorPose pose = camera_pose();
  Frame f{pose.position, {}, {}};
  const Vec3 forward = (pose.target - pose.position).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized(), up = right.cross(forward);
  const float fx = 0.5f * float(p.width) / std::tan(0.5f * p.fov_h_deg * float(M_PI) / 180.f);
  const float fy = 0.5f * float(p.height) / std::tan(0.5f * p.fov_v_deg * float(M_PI) / 180.f);
  for (int v = 0; v < p.height; ++v)
    for (int u = 0; u < p.width; ++u) {
      f.rays.push_back(forward + ((float(u) + 0.5f - 0.5f * float(p.width)) / fx) * right +
                       ((0.5f * float(p.height) - float(v) - 0.5f) / fy) * up);
      f.reach.push_back(p.max_range_m * f.rays.back().norm());
    }
  return f;
}

// A whole scan (noise, dropouts): BM_DepthCameraScan/<floor>/<whole frame>. The camera casts the window
// onto the scene's bounds (x/0); the baseline (x/1) casts every pixel, the same points.
void BM_DepthCameraScan(benchmark::State& state) {
  const RayScene& scene = chair_scene(state.range(0) != 0);
  DepthCameraParams params;
  params.whole_frame = state.range(1) != 0;
  size_t points = 0;
  for (auto _ : state) points = depth_camera_scan(scene, camera_pose(), params, 7).points.size();
  state.counters["points"] = double(points);
}
BENCHMARK(BM_DepthCameraScan)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

// The baseline: every pixel's ray on its own.
void BM_CastOneByOne(benchmark::State& state) {
  const RayScene& scene = chair_scene(state.range(0) != 0);
  const Frame f = camera_frame();
  for (auto _ : state) {
    size_t hits = 0;
    for (size_t i = 0; i < f.rays.size(); ++i) hits += scene.cast(f.origin, f.rays[i], f.reach[i]).hit;
    benchmark::DoNotOptimize(hits);
  }
}
BENCHMARK(BM_CastOneByOne)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Row by row, as the camera casts them.
void BM_CastRows(benchmark::State& state) {
  const RayScene& scene = chair_scene(state.range(0) != 0);
  const Frame f = camera_frame();
  const size_t width = size_t(DepthCameraParams{}.width);
  std::vector<RayScene::Hit> out(width);
  for (auto _ : state) {
    size_t hits = 0;
    for (size_t first = 0; first < f.rays.size(); first += width) {
      scene.cast_many(f.origin, std::span(f.rays).subspan(first, width), std::span(f.reach).subspan(first, width), out);
      for (const RayScene::Hit& h : out) hits += h.hit;
    }
    benchmark::DoNotOptimize(hits);
  }
}
BENCHMARK(BM_CastRows)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// A training camera's view as the recipe makes it, in two parts: the raw view (condition_view: the scene
// built and the frame cast) and the scan filters down to the model's density (filter_scan). Arg: the
// recipe's draw of the depth camera's pose (0-2; view 1 of each draw).
void BM_TrainingCameraView(benchmark::State& state) {
  static const Mesh mesh = *make_zoo_shape("chair", 1);
  const ScanCondition camera = default_training_sensors()[size_t(state.range(0))];
  ScanFilterParams filters;
  filters.relative_density = 3783.6;
  double raw_ms = 0, filter_ms = 0;
  size_t raw_points = 0, kept = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const Cloud raw = condition_view(mesh, false, {}, 1, 6, 42, camera, 6000, 100);
    const auto t1 = std::chrono::steady_clock::now();
    kept = filter_scan(raw, filters).points.size();
    const auto t2 = std::chrono::steady_clock::now();
    raw_points = raw.points.size();
    raw_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    filter_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
  }
  state.counters["raw_points"] = double(raw_points);
  state.counters["kept"] = double(kept);
  state.counters["view_ms"] = raw_ms / double(state.iterations());
  state.counters["filter_ms"] = filter_ms / double(state.iterations());
}
BENCHMARK(BM_TrainingCameraView)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
