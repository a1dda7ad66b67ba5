// Cost of a simulated depth camera's frame (the recipe's training views: 2400 of them in a cross-source
// run, twice with the size-blind ablation). BM_CastEveryPixel is the baseline in the same process: one
// ray through each of the 640 x 480 pixels, as the scan cast them before it skipped the rays that miss
// the scene's bounding box (a lower bound of the former scan's cost: no noise, no returns kept).
#include <benchmark/benchmark.h>

#include <cmath>

#include "glimpse/sensors.h"
#include "glimpse/zoo.h"

namespace {

using namespace glimpse;

struct Camera {
  RayScene scene;
  SensorPose pose;
};

// A zoo chair seen by the recipe's near training camera (1.5 m, 15 deg), with or without a floor patch.
Camera camera(bool floor) {
  Mesh m = *make_zoo_shape("chair", 1);
  const Bounds b = bounds(m.vertices);
  Camera c{*RayScene::build(m, floor ? 0.5f * std::max(b.extent().x(), b.extent().y()) + 0.5f : 0.f), {}};
  c.pose = orbit_pose(b.centre(), 0.f, 15.f, 1.5f);
  return c;
}

void BM_DepthCameraScan(benchmark::State& state) {
  const Camera c = camera(state.range(0) != 0);
  size_t points = 0;
  for (auto _ : state) points = depth_camera_scan(c.scene, c.pose, DepthCameraParams{}, 3).points.size();
  state.counters["points"] = double(points);
}
BENCHMARK(BM_DepthCameraScan)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_CastEveryPixel(benchmark::State& state) {
  const Camera c = camera(state.range(0) != 0);
  const DepthCameraParams p;
  const Vec3 forward = (c.pose.target - c.pose.position).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized(), up = right.cross(forward);
  const float fx = 0.5f * float(p.width) / std::tan(0.5f * p.fov_h_deg * 3.14159265f / 180.f);
  const float fy = 0.5f * float(p.height) / std::tan(0.5f * p.fov_v_deg * 3.14159265f / 180.f);
  for (auto _ : state) {
    size_t hits = 0;
    for (int v = 0; v < p.height; ++v)
      for (int u = 0; u < p.width; ++u) {
        const Vec3 ray = forward + ((float(u) + 0.5f - 0.5f * float(p.width)) / fx) * right +
                         ((0.5f * float(p.height) - float(v) - 0.5f) / fy) * up;
        hits += c.scene.cast(c.pose.position, ray, p.max_range_m * ray.norm()).hit;
      }
    benchmark::DoNotOptimize(hits);
  }
}
BENCHMARK(BM_CastEveryPixel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
