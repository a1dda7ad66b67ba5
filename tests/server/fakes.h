// Test doubles for the server: a deterministic fake Engine (no recogniser needed) whose failures can
// be switched on, and a harness that runs GlimpseService on an in-process channel over a :memory: store.
#pragma once

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "proto/wire/clouds.h"
#include "server/convert.h"
#include "server/engine.h"
#include "server/metrics.h"
#include "server/service.h"
#include "server/store.h"

namespace glimpse::server::testing {

// Knobs the fake reads on every call (tests flip them between calls).
struct FakeBehaviour {
  std::optional<Error> train_error;
  std::optional<Error> classify_error;
  std::optional<Error> session_error;
  std::optional<Error> deserialize_error;  // a stored (or just trained) model that does not read back
  bool classify_throws = false;
  bool train_waits_for_cancel = false;  // loops until the CancelFn says stop, then returns kCancelled
  std::atomic<int> deserialize_calls{0};
  std::atomic<int> train_calls{0};
  std::atomic<int> augmented_clouds{0};  // the last Train's clouds marked augmented
};

// "cats=a,b;methods=0,5;default=5" as bytes.
inline std::vector<uint8_t> FakeSerialize(const Model& m) {
  std::string s = "fake-model;cats=";
  for (size_t i = 0; i < m.categories.size(); ++i) s.append(i ? "," : "").append(m.categories[i]);
  s += ";methods=";
  for (size_t i = 0; i < m.methods.size(); ++i) s.append(i ? "," : "").append(std::to_string(int(m.methods[i])));
  s += ";default=" + std::to_string(int(m.default_method));
  return {s.begin(), s.end()};
}

inline std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string t; std::getline(in, t, sep);) out.push_back(t);
  return out;
}

inline Expected<Model> FakeDeserialize(std::span<const uint8_t> bytes) {
  std::string s(bytes.begin(), bytes.end());
  auto parts = Split(s, ';');
  if (parts.size() != 4 || parts[0] != "fake-model") return data_loss("not a fake model");
  Model m;
  m.categories = Split(parts[1].substr(5), ',');
  for (const auto& t : Split(parts[2].substr(8), ',')) m.methods.push_back(static_cast<MethodId>(std::stoi(t)));
  m.default_method = static_cast<MethodId>(std::stoi(parts[3].substr(8)));
  m.stats.categories = m.categories;
  return m;
}

// "None of these" in the fake: novelty = point count modulo 5, unknown above the threshold of the
// operating point: 2 for the model's default (known acceptance 0), 4 x known_acceptance otherwise.
inline double FakeThreshold(double known_acceptance) { return known_acceptance > 0 ? 4 * known_acceptance : 2.0; }
inline void FakeJudge(double known_acceptance, double novelty, bool& unknown, std::string& reason) {
  unknown = novelty > FakeThreshold(known_acceptance);
  reason = unknown ? "novelty " + std::to_string(int(novelty)) + " above the fake threshold" : "";
}
inline void FakeNovelty(size_t points, double known_acceptance, double& novelty, bool& unknown, std::string& reason) {
  novelty = double(points % 5);
  FakeJudge(known_acceptance, novelty, unknown, reason);
}

// Winner = point count modulo the number of categories; scores favour it. Deterministic.
inline Classification FakeScores(const Model& model, size_t points, MethodId method) {
  Classification c;
  c.method = method;
  c.categories = model.categories;
  const size_t n = model.categories.size();
  c.winner = static_cast<int>(points % n);
  c.scores.assign(n, n > 1 ? 0.3 / double(n - 1) : 1.0);
  c.scores[size_t(c.winner)] = n > 1 ? 0.7 : 1.0;
  c.points = points;
  c.keypoints = points / 10;
  c.feature_ms = 1.5;
  c.decision_ms = 0.5;
  FakeNovelty(points, 0, c.novelty, c.unknown, c.unknown_reason);
  return c;
}

class FakeSession final : public ScanSession {
 public:
  FakeSession(std::shared_ptr<const Model> model, MethodId method, FakeBehaviour* b, double known_acceptance = 0)
      : model_(std::move(model)), method_(method), b_(b), known_acceptance_(known_acceptance) {
    last_.categories = model_->categories;
    last_.scores.assign(model_->categories.size(), 0.0);
  }
  Expected<StreamDecision> add(const Cloud& chunk) override {
    if (b_->session_error) return *b_->session_error;
    points_ += chunk.points.size();
    Classification c = FakeScores(*model_, points_, method_);
    StreamDecision d;
    d.chunk_index = chunks_++;
    d.points = points_;
    d.keypoints = c.keypoints;
    d.categories = c.categories;
    d.scores = c.scores;
    d.raw_scores = c.scores;
    d.winner = c.winner;
    d.category_changes = last_.category_changes + (last_.winner >= 0 && last_.winner != d.winner ? 1 : 0);
    d.winner_held_chunks = last_.winner == d.winner ? last_.winner_held_chunks + 1 : 1;
    d.settled = d.winner_held_chunks >= 3;
    d.confidence = 0.7;
    FakeNovelty(points_, known_acceptance_, d.novelty, d.unknown, d.unknown_reason);
    last_ = d;
    return d;
  }
  Expected<StreamDecision> finish() override {
    last_.final = true;
    return last_;
  }
  const StreamDecision& last() const override { return last_; }

 private:
  std::shared_ptr<const Model> model_;
  MethodId method_;
  FakeBehaviour* b_;
  double known_acceptance_;
  StreamDecision last_;
  size_t points_ = 0;
  size_t chunks_ = 0;
};

// The fake's Train: categories and counts from the clouds, progress for each, no features.
inline decltype(Engine::train) FakeTrain(FakeBehaviour* b) {
  // The fake's training set is its categories, comma-separated: a grown model learns the base's too.
  return [b](const std::vector<TrainingCloud>& data, const wire::TrainSpec& spec, std::span<const uint8_t> base_set,
                std::span<const uint8_t>, size_t keep_set_bytes, const ProgressFn& progress,
                const CancelFn& cancel) -> Expected<TrainedModel> {
    ++b->train_calls;
    if (b->train_error) return *b->train_error;
    if (b->train_waits_for_cancel) {
      for (int i = 0; i < 3000 && !(cancel && cancel()); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      return cancelled("training cancelled");
    }
    std::set<std::string> cats, objects;
    for (std::string base(base_set.begin(), base_set.end()), c; !base.empty(); base.erase(0, c.size() + 1)) {
      c = base.substr(0, base.find(','));
      cats.insert(c);
    }
    size_t points = 0;
    b->augmented_clouds = int(std::count_if(data.begin(), data.end(), [](const TrainingCloud& d) { return d.augmented; }));
    for (const auto& d : data) {
      cats.insert(d.category);
      objects.insert(d.object_id);
      points += d.cloud.points.size();
    }
    if (cats.size() < 2) return failed_precondition("training needs at least 2 categories");  // as core
    for (size_t i = 0; i < data.size(); ++i)
      if (progress) progress({"features", i + 1, data.size()});
    if (progress) progress({"codebooks", 1, 1});
    Model m;
    m.categories.assign(cats.begin(), cats.end());
    m.methods = spec.methods.empty() ? std::vector<MethodId>{MethodId::kBoK, MethodId::kFusion} : spec.methods;
    m.default_method = spec.default_method.value_or(m.methods.back());
    m.stats.clouds = data.size();
    m.stats.objects = objects.size();
    m.stats.keypoints = points / 10;
    m.stats.categories = m.categories;
    for (const auto& c : m.categories)
      m.stats.clouds_per_category.push_back(
          size_t(std::count_if(data.begin(), data.end(), [&](const TrainingCloud& d) { return d.category == c; })));
    m.stats.seconds = 0.25;
    std::string set;
    for (const auto& c : m.categories) set += (set.empty() ? "" : ",") + c;
    TrainedModel out{m, {}};
    if (set.size() <= keep_set_bytes) out.training_set.assign(set.begin(), set.end());
    return out;
  };
}

inline Engine FakeEngine(FakeBehaviour* b) {
  Engine e;
  e.train = FakeTrain(b);
  e.classify = [b](const Model& model, const Cloud& cloud, std::optional<MethodId> method,
                   const CancelFn& cancel) -> Expected<Classification> {
    if (b->classify_throws) throw std::runtime_error("boom");
    if (b->classify_error) return *b->classify_error;
    if (cancel && cancel()) return cancelled("classification cancelled");
    MethodId m = method.value_or(model.default_method);
    if (std::find(model.methods.begin(), model.methods.end(), m) == model.methods.end())
      return failed_precondition("the model was not trained for this method");  // as core
    if (cloud.points.size() < 3) return invalid_argument("too few points");
    Classification c = FakeScores(model, cloud.points.size(), m);
    if (cloud.points.size() >= 5000) c.warning = "the cloud is large";
    return c;
  };
  e.classify_batch = [classify = e.classify](const Model& model, std::span<const Cloud> clouds,
                                             std::optional<MethodId> method, const CancelFn& cancel) {
    std::vector<Expected<Classification>> out;
    for (const Cloud& c : clouds) out.push_back(classify(model, c, method, cancel));
    return out;
  };
  e.set_known_acceptance = [](const Model&, Classification& c, double known_acceptance) -> Status {
    FakeJudge(known_acceptance, c.novelty, c.unknown, c.unknown_reason);
    return {};
  };
  e.serialize = [](const Model& m) { return FakeSerialize(m); };
  e.deserialize = [b](std::span<const uint8_t> bytes) {
    ++b->deserialize_calls;
    if (b->deserialize_error) return Expected<Model>(*b->deserialize_error);
    return FakeDeserialize(bytes);
  };
  e.create_session = [b](std::shared_ptr<const Model> model,
                         const SessionParams& p) -> Expected<std::unique_ptr<ScanSession>> {
    MethodId m = p.method.value_or(model->default_method);
    return std::unique_ptr<ScanSession>(new FakeSession(std::move(model), m, b, p.known_acceptance));
  };
  return e;
}

// A cloud of n points on a line-free spiral (no NaNs), offset by `shift`.
inline Cloud SpiralCloud(size_t n, float shift = 0) {
  Cloud c;
  for (size_t i = 0; i < n; ++i) {
    float t = 0.1f * float(i);
    c.points.emplace_back(std::cos(t) + shift, std::sin(t), 0.01f * float(i));
  }
  return c;
}

// GlimpseService on an in-process channel over a :memory: store with the fake engine.
struct Harness {
  explicit Harness(Limits limits = {}, std::function<void(ServiceOptions&)> tweak = {},
                   std::string db = ":memory:") {
    auto opened = ModelStore::Open(db);
    if (!opened) throw std::runtime_error(opened.error().message);
    store = std::move(*opened);
    ServiceOptions o;
    o.store = store.get();
    o.engine = FakeEngine(&behaviour);
    o.limits = limits;
    o.metrics = &metrics;
    o.log = [this](const RequestLog& l) {
      std::lock_guard lock(log_mutex);
      logs.push_back(l);
    };
    o.reap_interval = std::chrono::milliseconds(0);
    if (tweak) tweak(o);
    service = std::make_unique<GlimpseService>(std::move(o));
    grpc::ServerBuilder builder;
    builder.RegisterService(service.get());
    builder.SetMaxReceiveMessageSize(int(std::min<size_t>(limits.max_message_bytes, INT_MAX)));
    server = builder.BuildAndStart();
    stub = v1::Glimpse::NewStub(server->InProcessChannel(grpc::ChannelArguments()));
  }
  ~Harness() {
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
    server->Wait();
  }

  // Trains a model named `name` over `per_category` clouds of each category; returns the final message.
  grpc::Status Train(const std::string& name, const std::vector<std::string>& categories, v1::TrainProgress* last,
                     int per_category = 2, const std::function<void(v1::TrainHeader&)>& tweak = {}) {
    grpc::ClientContext ctx;
    auto stream = stub->Train(&ctx);
    v1::TrainRequest header;
    header.mutable_header()->set_model_name(name);
    if (tweak) tweak(*header.mutable_header());
    stream->Write(header);
    for (size_t c = 0; c < categories.size(); ++c)
      for (int i = 0; i < per_category; ++i) {
        v1::TrainRequest req;
        req.mutable_cloud()->set_category(categories[c]);
        req.mutable_cloud()->set_object_id(categories[c] + std::to_string(i));
        *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(50 + 10 * c + i, float(c)));
        stream->Write(req);
      }
    stream->WritesDone();
    v1::TrainProgress p;
    while (stream->Read(&p)) *last = p;
    return stream->Finish();
  }

  std::vector<RequestLog> Logs() {
    std::lock_guard lock(log_mutex);
    return logs;
  }

  FakeBehaviour behaviour;
  std::unique_ptr<ModelStore> store;
  Metrics metrics;
  std::mutex log_mutex;
  std::vector<RequestLog> logs;
  std::unique_ptr<GlimpseService> service;
  std::unique_ptr<grpc::Server> server;
  std::unique_ptr<v1::Glimpse::Stub> stub;
};

}  // namespace glimpse::server::testing
