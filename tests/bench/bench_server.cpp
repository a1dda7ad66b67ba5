// The service's speed goal: Classify over a real loopback gRPC port against glimpse::classify called in
// process, on the same trained model and the same 10,000-point single view; the gRPC overhead (wire
// encoding, HTTP/2, the store lookup, the cache) stays <= 10 % of the call. Also the Classify
// throughput of one server with 2 client threads, in requests/s.
// The batch goal: 32 views in one ClassifyBatch call against 32 Classify calls one after the other, over
// loopback, same server (the batch takes <= 0.8 of the singles' time). On a 2-core VM, medians of 5:
// batch 85.8 ms, singles 142.7 ms, ratio 0.60 (a batch spreads its clouds over the request's threads,
// one thread per cloud).
//   bench_server --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// After the table it prints the overhead ratio and the batch ratio of the medians (or of single runs).
#include <benchmark/benchmark.h>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>

#include "glimpse/learning/train_params.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/zoo.h"
#include "proto/wire/clouds.h"
#include "server/server.h"
#include "server/service.h"
#include "tests/common/temp_dir.h"  // the project root is on the path through the server library

namespace glimpse::server {
namespace {

constexpr size_t kViewPoints = 10'000;
constexpr const char* kModelName = "bench";

// Training set: single views (hidden point removal from the paper's six viewpoints, two of them) of
// three zoo shapes per category, as `glimpse train --zoo --views 2` builds them.
std::vector<TrainingCloud> TrainingViews() {
  std::vector<TrainingCloud> data;
  for (const LabelledMesh& m : make_zoo(3, /*seed=*/1)) {
    const Cloud full = mesh_vertices(m.mesh);
    const std::vector<Vec3> cameras = paper_viewpoints(full.points);
    for (size_t v = 0; v < cameras.size(); v += 3)
      data.push_back({m.category, m.category + std::to_string(m.seed), hidden_point_removal(full.points, cameras[v])});
  }
  return data;
}

// A single view of a zoo human not in the training set, with exactly kViewPoints points: the
// surface is sampled densely, seen from viewpoint 1, and a seeded subset of the visible points kept.
Cloud QueryView() {
  const Mesh mesh = *make_zoo_shape("human", 1001);
  const Cloud full = sample_surface(mesh, 4.0 * kViewPoints / std::max(1e-6, surface_area(mesh)), 7);
  Cloud view = hidden_point_removal(full.points, paper_viewpoints(full.points)[1]);
  std::mt19937 rng(7);
  std::shuffle(view.points.begin(), view.points.end(), rng);
  if (view.points.size() > kViewPoints) view.points.resize(kViewPoints);
  return view;
}

// 32 protocol views (6000 surface samples, paper viewpoint 1, as glimpse-lab and `glimpse evaluate`
// make them) of zoo objects the model did not learn.
constexpr size_t kBatchViews = 32;
std::vector<Cloud> BatchViews() {
  std::vector<Cloud> views;
  for (const LabelledMesh& o : make_zoo(7, /*seed=*/77)) {
    if (views.size() == kBatchViews) break;
    const uint64_t seed = object_seed(77, o.category + "/" + o.id);
    views.push_back(object_view(object_cloud(o.mesh, 6000, seed), 1, 6, o.any_pose, seed));
  }
  return views;
}

// One trained model, a server holding it in a temporary SQLite file on 127.0.0.1:<free port>, and
// the query view; built once, on first use.
struct Fixture {
  std::shared_ptr<const Model> model;
  Cloud view;
  v1::ClassifyRequest request;
  v1::ClassifyBatchRequest batch;           // kBatchViews clouds
  std::vector<v1::ClassifyRequest> singles; // the same clouds, one request each
  glimpse::testing::TempDir dir{"bench-server"};  // the store's SQLite file
  std::unique_ptr<ModelStore> store;
  std::unique_ptr<GlimpseService> service;
  RunningServer running;
  std::shared_ptr<grpc::Channel> channel;
  std::string error;  // set when any step failed

  Fixture() {
    TrainParams params;  // core's defaults (the paper's settings), default method: fusion
    auto trained = train(TrainingViews(), params);
    if (!trained) {
      error = "train: " + trained.error().message;
      return;
    }
    model = std::make_shared<const Model>(std::move(*trained));
    view = QueryView();
    if (view.points.size() != kViewPoints) {
      error = "the query view has " + std::to_string(view.points.size()) + " points, not " + std::to_string(kViewPoints);
      return;
    }

    auto opened = ModelStore::Open(dir.file("glimpse.db"));
    if (!opened) {
      error = "store: " + opened.error().message;
      return;
    }
    store = std::move(*opened);
    NewModel stored{kModelName, "bench_server", model->methods, model->default_method, "{}", model->stats,
                    serialize(*model)};
    if (auto put = store->Put(stored); !put) {
      error = "store put: " + put.error().message;
      return;
    }
    ServiceOptions o;
    o.store = store.get();
    o.engine = CoreEngine();
    o.log = [](const RequestLog&) {};  // one stderr line per call would be measured too
    service = std::make_unique<GlimpseService>(std::move(o));
    GrpcServerOptions g;
    g.address = "127.0.0.1:0";
    g.threads = 8;
    auto started = StartGrpcServer(g, service.get());
    if (!started) {
      error = "server: " + started.error().message;
      return;
    }
    running = std::move(*started);
    channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(running.port), grpc::InsecureChannelCredentials());

    request.mutable_model()->set_name(kModelName);
    *request.mutable_cloud() = wire::CloudToProto(view);
    batch.mutable_model()->set_name(kModelName);
    for (const Cloud& c : BatchViews()) {
      *batch.add_clouds() = wire::CloudToProto(c);
      singles.push_back(request);
      *singles.back().mutable_cloud() = wire::CloudToProto(c);
    }
    error = CheckSameAnswer();  // also loads the model into the server's cache
  }

  ~Fixture() {
    if (running.server) ShutdownGrpcServer(*running.server, std::chrono::seconds(2));
    service.reset();
    store.reset();
  }

  // Both paths must compute the same thing, or the comparison means nothing.
  std::string CheckSameAnswer() {
    auto direct = classify(*model, view);
    if (!direct) return "in-process classify: " + direct.error().message;
    v1::ClassifyResponse response;
    grpc::ClientContext ctx;
    const grpc::Status s = v1::Glimpse::NewStub(channel)->Classify(&ctx, request, &response);
    if (!s.ok()) return "Classify over gRPC: " + s.error_message();
    if (response.winner_index() != direct->winner || response.points() != direct->points)
      return "gRPC and in-process answers differ (winner " + response.winner() + " vs " +
             direct->categories[size_t(direct->winner)] + ")";
    return {};
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

void BM_ClassifyInProcess(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.error.empty()) return state.SkipWithError(f.error.c_str());
  size_t keypoints = 0;
  for (auto _ : state) {
    auto c = classify(*f.model, f.view);
    if (!c) return state.SkipWithError(c.error().message.c_str());
    keypoints = c->keypoints;
    benchmark::DoNotOptimize(c);
  }
  state.counters["points"] = double(f.view.points.size());
  state.counters["keypoints"] = double(keypoints);
}

// One Classify call per iteration, a channel per thread; `server_ms` is the server's own time for
// the call (request decoded to response built), so real time minus it is the wire and gRPC cost.
void BM_ClassifyLoopback(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.error.empty()) return state.SkipWithError(f.error.c_str());
  grpc::ChannelArguments args;
  args.SetInt("glimpse.bench.thread", state.thread_index());  // distinct args: a connection per thread
  auto stub = v1::Glimpse::NewStub(grpc::CreateCustomChannel(
      "127.0.0.1:" + std::to_string(f.running.port), grpc::InsecureChannelCredentials(), args));
  double server_ms = 0;
  for (auto _ : state) {
    v1::ClassifyResponse response;
    grpc::ClientContext ctx;
    const grpc::Status s = stub->Classify(&ctx, f.request, &response);
    if (!s.ok()) return state.SkipWithError(("Classify: " + s.error_message()).c_str());
    server_ms += response.timings().total_ms();
  }
  state.SetItemsProcessed(state.iterations());  // items/s = requests/s
  state.counters["server_ms"] = benchmark::Counter(server_ms, benchmark::Counter::kAvgIterations);
}

// 32 Classify calls, one after the other, from one client thread.
void BM_Singles32(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.error.empty()) return state.SkipWithError(f.error.c_str());
  auto stub = v1::Glimpse::NewStub(f.channel);
  for (auto _ : state)
    for (const v1::ClassifyRequest& r : f.singles) {
      v1::ClassifyResponse response;
      grpc::ClientContext ctx;
      const grpc::Status s = stub->Classify(&ctx, r, &response);
      if (!s.ok()) return state.SkipWithError(("Classify: " + s.error_message()).c_str());
    }
  state.counters["clouds"] = double(f.singles.size());
}

// The same 32 clouds in one ClassifyBatch call; every result must be OK.
void BM_Batch32(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.error.empty()) return state.SkipWithError(f.error.c_str());
  auto stub = v1::Glimpse::NewStub(f.channel);
  for (auto _ : state) {
    v1::ClassifyBatchResponse response;
    grpc::ClientContext ctx;
    const grpc::Status s = stub->ClassifyBatch(&ctx, f.batch, &response);
    if (!s.ok()) return state.SkipWithError(("ClassifyBatch: " + s.error_message()).c_str());
    for (const v1::ClassifyResult& r : response.results())
      if (r.code() != 0) return state.SkipWithError(("a batch result failed: " + r.message()).c_str());
  }
  state.counters["clouds"] = double(f.batch.clouds_size());
}

BENCHMARK(BM_Singles32)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_Batch32)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_ClassifyInProcess)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();
BENCHMARK(BM_ClassifyLoopback)->Threads(1)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();
BENCHMARK(BM_ClassifyLoopback)->Threads(2)->Unit(benchmark::kMillisecond)->MinTime(4.0)->UseRealTime();

// The console table, plus the real time of each benchmark's median (or of its only run) kept for
// the ratio printed at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  // Colours only on a terminal, so a log file stays plain text.
  RatioReporter() : ConsoleReporter(::isatty(STDOUT_FILENO) ? OO_ColorTabular : OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      const bool single = r.run_type == Run::RT_Iteration && r.repetitions <= 1;
      if (!median && !single) continue;
      const std::string key = r.run_name.function_name + "/" + r.run_name.threads;  // "BM_X/threads:2"
      times_ms[key] = r.GetAdjustedRealTime();
      if (r.counters.count("items_per_second")) requests_per_s[key] = r.counters.at("items_per_second");
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times_ms, requests_per_s;
};

}  // namespace
}  // namespace glimpse::server

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  glimpse::server::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& t = reporter.times_ms;
  const auto in_process = t.find("BM_ClassifyInProcess/"), loopback = t.find("BM_ClassifyLoopback/threads:1");
  if (in_process != t.end() && loopback != t.end() && in_process->second > 0) {
    const double ratio = loopback->second / in_process->second;
    std::printf("\nClassify, %zu-point view: in-process %.2f ms, loopback gRPC %.2f ms: ratio %.3f, overhead %+.1f %% "
                "(goal <= 10 %%: %s)\n",
                glimpse::server::kViewPoints, in_process->second, loopback->second, ratio, 100 * (ratio - 1),
                ratio <= 1.10 ? "met" : "not met");
  }
  const auto singles = t.find("BM_Singles32/"), batch = t.find("BM_Batch32/");
  if (singles != t.end() && batch != t.end() && singles->second > 0) {
    const double ratio = batch->second / singles->second;
    std::printf("%zu views: one ClassifyBatch %.1f ms, %zu Classify calls %.1f ms: ratio %.3f (goal <= 0.8: %s)\n",
                glimpse::server::kBatchViews, batch->second, glimpse::server::kBatchViews, singles->second, ratio,
                ratio <= 0.8 ? "met" : "not met");
  }
  for (const auto& [name, rps] : reporter.requests_per_s)
    std::printf("%s: %.2f requests/s\n", name.c_str(), rps);
  benchmark::Shutdown();
  return 0;
}
