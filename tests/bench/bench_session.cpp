// Per-chunk latency of a ScanSession: 1k-point chunks of one object revealed top-down, from the 1st to the
// 50th chunk. The cost of a chunk depends on the chunk, not on what was accumulated. Goal: the 50th chunk
// <= 1.5x the 5th (compare the medians of one run). Measured (2-core VM, shared with a compile job): BoK
// 50th / 5th = 22.6 / 34.7 ms = 0.65, fusion 24.2 / 20.9 = 1.16, fusion window (BM_SessionWindow: the mean
// of chunks 41-50 over that of chunks 5-14) 24.9 / 18.9 ms = 1.32.
#include <benchmark/benchmark.h>

#include "../core/synthetic.h"
#include "glimpse/session/session.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/exploration.h"
#include "glimpse/views/zoo.h"

#include <Eigen/Geometry>

namespace glimpse {
namespace {

constexpr size_t kChunkPoints = 1000;
constexpr size_t kChunks = 50;

// A dense single view of a procedural chair, tilted by 10 degrees so that its seat is not one
// horizontal plane revealed all at once: at least 50k points, revealed top-down.
const std::vector<Cloud>& chunks() {
  static const std::vector<Cloud> c = [] {
    Mesh mesh = *make_zoo_shape("chair", 7);
    const Eigen::Matrix3f tilt = Eigen::AngleAxisf(0.17f, Vec3::UnitX()).toRotationMatrix();
    for (Vec3& v : mesh.vertices) v = tilt * v;
    const Cloud full = sample_surface(mesh, 60000.0 / std::max(1e-6, surface_area(mesh)) * 2.5, 7);
    const Cloud view = hidden_point_removal(full.points, paper_viewpoints(full.points)[1]);
    const std::vector<uint32_t> order = top_down_order(view.points);
    std::vector<Cloud> out(std::min(kChunks, order.size() / kChunkPoints));
    for (size_t i = 0; i < out.size() * kChunkPoints; ++i) {
      out[i / kChunkPoints].sensor = view.sensor;
      out[i / kChunkPoints].points.push_back(view.points[order[i]]);
    }
    return out;
  }();
  return c;
}

std::shared_ptr<const Model> model(MethodId method) {
  TrainParams p = test::small_params();
  p.methods = {method};
  p.default_method = method;
  auto m = train(test::synthetic_views(4, 2, 3), p);
  return m.ok() ? std::make_shared<const Model>(std::move(*m)) : nullptr;
}

// Latency of chunk number state.range(0) (1-based), after feeding the ones before it untimed.
void BM_SessionChunk(benchmark::State& state, MethodId method) {
  static std::shared_ptr<const Model> bok = model(MethodId::kBoK), fusion = model(MethodId::kFusion);
  const auto& m = method == MethodId::kBoK ? bok : fusion;
  const size_t k = static_cast<size_t>(state.range(0));
  if (!m || chunks().size() < k) {
    state.SkipWithError("no model or too few chunks");
    return;
  }
  size_t points = 0, keypoints = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto session = *ScanSession::create(m);
    for (size_t i = 0; i + 1 < k; ++i) (void)session->add(chunks()[i]);
    state.ResumeTiming();
    auto d = session->add(chunks()[k - 1]);
    benchmark::DoNotOptimize(d);
    points = d->points, keypoints = d->keypoints;
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["keypoints"] = static_cast<double>(keypoints);
}
// Whole-cloud descriptors (VFH, ESF in fusion) are refreshed when the scan grew by
// SessionParams::global_refresh_growth, so one chunk may pay a refresh and the next none: their
// per-chunk cost is the mean over the 10 chunks from state.range(0) on (amortised).
void BM_SessionWindow(benchmark::State& state, MethodId method) {
  static std::shared_ptr<const Model> bok = model(MethodId::kBoK), fusion = model(MethodId::kFusion);
  const auto& m = method == MethodId::kBoK ? bok : fusion;
  const size_t first = static_cast<size_t>(state.range(0)), window = 10;
  if (!m || chunks().size() < first + window - 1) {
    state.SkipWithError("no model or too few chunks");
    return;
  }
  for (auto _ : state) {
    state.PauseTiming();
    auto session = *ScanSession::create(m);
    for (size_t i = 0; i + 1 < first; ++i) (void)session->add(chunks()[i]);
    state.ResumeTiming();
    for (size_t i = first - 1; i < first - 1 + window; ++i) benchmark::DoNotOptimize(session->add(chunks()[i]));
  }
  state.counters["s_per_chunk"] = benchmark::Counter(static_cast<double>(window) * static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK_CAPTURE(BM_SessionWindow, fusion, MethodId::kFusion)->Arg(5)->Arg(41)->Iterations(3)->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(BM_SessionChunk, bok, MethodId::kBoK)->Arg(1)->Arg(5)->Arg(25)->Arg(50)->Iterations(5)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SessionChunk, fusion, MethodId::kFusion)->Arg(5)->Arg(50)->Iterations(5)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace glimpse

BENCHMARK_MAIN();
