// The bad-input table: every malformed, degenerate or over-limit request a client
// can send, against a real loopback server with the real recogniser trained on zoo shapes. Each row
// names the call, the status code it must get and a piece of the message that says why; after every
// row the server must still report SERVING and classify a good view exactly as before, and no failed
// Train may have stored anything. The fake-engine unit tests (tests/server/test_service.cpp) check
// the same codes in isolation; this table checks them through core, end to end.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>

#include "real_server.h"

namespace glimpse::reliability {
namespace {

using grpc::StatusCode;
using wire::CloudToProto;

// Small limits, so that every "over the limit" row is cheap.
Limits TableLimits() {
  Limits l;
  l.max_points_per_cloud = 50'000;
  l.max_message_bytes = 4u << 20;
  l.max_session_points = 20'000;
  l.max_train_clouds = 40;
  l.max_concurrent_streams = 4;
  return l;
}

// ---- clouds ---------------------------------------------------------------------------------

Cloud Noise(size_t n, float scale, float offset = 0, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  Cloud c;
  for (size_t i = 0; i < n; ++i) c.points.emplace_back(offset + scale * u(rng), scale * u(rng), scale * u(rng));
  return c;
}
Cloud Line(size_t n) {
  Cloud c;
  for (size_t i = 0; i < n; ++i) c.points.emplace_back(0.001f * float(i), 0.002f * float(i), 0.003f * float(i));
  return c;
}
Cloud Plane(size_t n) {
  Cloud c = Noise(n, 0.5f);
  for (Vec3& p : c.points) p.z() = 0;
  return c;
}
Cloud Same(size_t n) { return Cloud{Points(n, Vec3(0.1f, 0.2f, 0.3f)), std::nullopt, {}}; }
Cloud With(Cloud c, size_t i, Vec3 p) {
  c.points.at(i) = p;
  return c;
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- the fixture: one server, one model, one good view --------------------------------------

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("bad-input");
    server_ = new RealServer(dir_->file("models.db"), TableLimits());
    train_ = new std::vector<TrainingCloud>(ZooViews(2, 7, 2));
    grpc::Status s = TrainStream(*server_->stub, TrainMessages(FastTrainHeader("zoo"), *train_));
    ASSERT_TRUE(s.ok()) << s.error_message();
    v1::TrainHeader esf = FastTrainHeader("zoo-esf");
    esf.add_methods(v1::METHOD_ESF);
    s = TrainStream(*server_->stub, TrainMessages(esf, *train_));
    ASSERT_TRUE(s.ok()) << s.error_message();
    good_ = new Cloud(ZooViews(1, 99, 1)[0].cloud);  // a chair of an unseen seed
    reference_ = new v1::ClassifyResponse;
    s = Classify(*good_, "zoo", reference_);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }
  static void TearDownTestSuite() {
    delete server_;
    delete dir_;
    delete train_;
    delete good_;
    delete reference_;
  }

  static grpc::Status Classify(const v1::ClassifyRequest& req, v1::ClassifyResponse* resp = nullptr,
                               std::chrono::milliseconds deadline = std::chrono::seconds(60)) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + deadline);
    v1::ClassifyResponse local;
    return server_->stub->Classify(&ctx, req, resp ? resp : &local);
  }
  static v1::ClassifyRequest Request(const Cloud& cloud, const std::string& model = "zoo") {
    v1::ClassifyRequest req;
    req.mutable_model()->set_name(model);
    *req.mutable_cloud() = wire::CloudToProto(cloud);
    return req;
  }
  static grpc::Status Classify(const Cloud& cloud, const std::string& model = "zoo",
                               v1::ClassifyResponse* resp = nullptr) {
    return Classify(Request(cloud, model), resp);
  }

  // Sends the chunks one by one, reading a decision after each; stops at the first failure.
  static grpc::Status Stream(const std::vector<v1::ScanChunk>& chunks) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto stream = server_->stub->StreamClassify(&ctx);
    for (const auto& c : chunks) {
      if (!stream->Write(c)) break;
      v1::Decision d;
      if (!stream->Read(&d)) break;
    }
    stream->WritesDone();
    for (v1::Decision rest; stream->Read(&rest);) {}
    return stream->Finish();
  }
  static v1::ScanChunk Chunk(const Cloud& cloud, const std::string& model = "") {
    v1::ScanChunk c;
    if (!model.empty()) c.mutable_model()->set_name(model);
    *c.mutable_cloud() = wire::CloudToProto(cloud);
    return c;
  }
  static std::vector<v1::ScanChunk> Chunks(const Cloud& cloud, size_t n, const std::string& model = "zoo") {
    std::vector<v1::ScanChunk> out;
    const size_t per = (cloud.points.size() + n - 1) / n;
    for (size_t k = 0; k < n; ++k) {
      Cloud part;
      for (size_t i = k * per; i < std::min(cloud.points.size(), (k + 1) * per); ++i) part.points.push_back(cloud.points[i]);
      out.push_back(Chunk(part, k == 0 ? model : ""));
    }
    return out;
  }

  static v1::TrainRequest HeaderMsg(const std::function<void(v1::TrainHeader&)>& tweak = {}) {
    v1::TrainRequest r;
    *r.mutable_header() = FastTrainHeader("zoo-bad");
    if (tweak) tweak(*r.mutable_header());
    return r;
  }
  // The good training set with the clouds of `category` replaced by `clouds`.
  static std::vector<v1::TrainRequest> TrainWith(const std::string& category, const std::vector<Cloud>& clouds) {
    std::vector<v1::TrainRequest> msgs{HeaderMsg()};
    for (const TrainingCloud& lc : *train_)
      if (lc.category != category) msgs.push_back(CloudMessage(lc));
    for (size_t i = 0; i < clouds.size(); ++i) msgs.push_back(CloudMessage({category, category + std::to_string(i), clouds[i]}));
    return msgs;
  }
  static std::vector<v1::TrainRequest> GoodTrain(const std::function<void(v1::TrainHeader&)>& tweak = {}) {
    std::vector<v1::TrainRequest> msgs{HeaderMsg(tweak)};
    for (const TrainingCloud& lc : *train_) msgs.push_back(CloudMessage(lc));
    return msgs;
  }

  static TempDir* dir_;
  static RealServer* server_;
  static std::vector<TrainingCloud>* train_;
  static Cloud* good_;
  static v1::ClassifyResponse* reference_;
};

TempDir* BadInput::dir_ = nullptr;
RealServer* BadInput::server_ = nullptr;
std::vector<TrainingCloud>* BadInput::train_ = nullptr;
Cloud* BadInput::good_ = nullptr;
v1::ClassifyResponse* BadInput::reference_ = nullptr;

struct Row {
  std::string name;
  std::function<grpc::Status()> call;
  StatusCode code;
  std::string message;  // a piece of the status message
};

const char* CodeName(StatusCode c) { return wire::StatusCodeName(c); }

TEST_F(BadInput, EveryCaseGetsItsStatusAndTheServerKeepsServing) {
  ASSERT_NE(server_, nullptr);
  using B = BadInput;
  const Cloud& good = *good_;
  const auto bok = [](v1::ClassifyRequest r) {
    r.set_method(v1::METHOD_BOK);
    return r;
  };
  std::vector<Row> rows = {
      // ---- Classify: the cloud
      {"classify NaN x", [&] { return B::Classify(With(good, 5, Vec3(kNaN, 0, 0))); }, StatusCode::INVALID_ARGUMENT,
       "xyz: point 5 is not finite"},
      {"classify +Inf z", [&] { return B::Classify(With(good, 9, Vec3(0, 0, kInf))); }, StatusCode::INVALID_ARGUMENT,
       "xyz: point 9 is not finite"},
      {"classify -Inf y", [&] { return B::Classify(With(good, 0, Vec3(0, -kInf, 0))); }, StatusCode::INVALID_ARGUMENT,
       "xyz: point 0 is not finite"},
      {"classify empty cloud", [&] { return B::Classify(Cloud{}); }, StatusCode::INVALID_ARGUMENT, "the cloud is empty"},
      {"classify one point", [&] { return B::Classify(Same(1)); }, StatusCode::INVALID_ARGUMENT, "1 usable point after"},
      {"classify 19 points (core needs 20)", [&] { return B::Classify(Noise(19, 0.3f)); }, StatusCode::INVALID_ARGUMENT,
       "19 usable points"},
      {"classify 3000 copies of one point", [&] { return B::Classify(Same(3000)); }, StatusCode::INVALID_ARGUMENT,
       "1 usable point after"},
      {"classify collinear points", [&] { return B::Classify(Line(3000)); }, StatusCode::INVALID_ARGUMENT, "collinear"},
      {"classify points 1e-30 m apart", [&] { return B::Classify(Noise(3000, 1e-30f)); }, StatusCode::INVALID_ARGUMENT,
       "every point coincides"},
      {"classify a flat square (valid, no keypoints)", [&] { return B::Classify(Plane(3000)); }, StatusCode::OK, ""},
      {"classify coordinates of 1e30 m", [&] { return B::Classify(Noise(3000, 1e30f)); }, StatusCode::INVALID_ARGUMENT,
       "beyond +-1e6 m"},
      {"classify 3e38 m (aborted the server before)", [&] { return B::Classify(Noise(3000, 3e38f)); },
       StatusCode::INVALID_ARGUMENT, "beyond +-1e6 m"},
      {"classify one point 1e30 m away from a good view", [&] { return B::Classify(With(good, 3, Vec3(1e30f, 0, 0))); },
       StatusCode::INVALID_ARGUMENT, "point 3 has a coordinate beyond"},
      {"classify xyz of 121 bytes",
       [&] {
         auto r = B::Request(Noise(10, 0.3f));
         r.mutable_cloud()->mutable_xyz()->push_back('x');
         return B::Classify(r);
       },
       StatusCode::INVALID_ARGUMENT, "multiple of 12"},
      {"classify normals shorter than xyz",
       [&] {
         auto r = B::Request(good);
         r.mutable_cloud()->set_normals(std::string(24, '\0'));
         return B::Classify(r);
       },
       StatusCode::INVALID_ARGUMENT, "normals has 24 bytes"},
      {"classify NaN normal",
       [&] {
         auto r = B::Request(good);
         r.mutable_cloud()->set_normals(wire::PackPoints(With(good, 2, Vec3(kNaN, 0, 0)).points));
         return B::Classify(r);
       },
       StatusCode::INVALID_ARGUMENT, "normals: point 2 is not finite"},
      {"classify NaN sensor",
       [&] {
         auto r = B::Request(good);
         r.mutable_cloud()->mutable_sensor()->set_y(kNaN);
         return B::Classify(r);
       },
       StatusCode::INVALID_ARGUMENT, "sensor position is not finite"},
      {"classify 50001 points (limit 50000)", [&] { return B::Classify(Noise(50'001, 0.3f)); },
       StatusCode::RESOURCE_EXHAUSTED, "the limit is 50000"},
      {"classify a 6 MB message (limit 4 MiB)", [&] { return B::Classify(Noise(500'000, 0.3f)); },
       StatusCode::RESOURCE_EXHAUSTED, "larger than max"},
      // ---- Classify: model and method
      {"classify unknown model", [&] { return B::Classify(good, "no-such-model"); }, StatusCode::NOT_FOUND,
       "no-such-model"},
      {"classify unknown version",
       [&] {
         auto r = B::Request(good);
         r.mutable_model()->set_version(42);
         return B::Classify(r);
       },
       StatusCode::NOT_FOUND, "42"},
      {"classify empty model name", [&] { return B::Classify(good, ""); }, StatusCode::INVALID_ARGUMENT,
       "model name is empty"},
      {"classify model name with a slash", [&] { return B::Classify(good, "../etc"); }, StatusCode::INVALID_ARGUMENT,
       "may only contain"},
      {"classify unknown method 99",
       [&] {
         auto r = B::Request(good);
         r.set_method(static_cast<v1::Method>(99));
         return B::Classify(r);
       },
       StatusCode::INVALID_ARGUMENT, "unknown method 99"},
      {"classify with a method the model lacks", [&] { return B::Classify(bok(B::Request(good, "zoo-esf"))); },
       StatusCode::FAILED_PRECONDITION, "not trained for method 'bok'"},
      {"classify with a deadline already passed",
       [&] { return B::Classify(B::Request(good), nullptr, std::chrono::milliseconds(-1)); },
       StatusCode::DEADLINE_EXCEEDED, ""},
      // ---- Train: message order and content
      {"train with no message", [&] { return TrainStream(*server_->stub, {}); }, StatusCode::INVALID_ARGUMENT,
       "needs a header"},
      {"train cloud before header",
       [&] { return TrainStream(*server_->stub, {CloudMessage(train_->at(0)), B::HeaderMsg()}); },
       StatusCode::INVALID_ARGUMENT, "first Train message must be the header"},
      {"train header twice", [&] { return TrainStream(*server_->stub, {B::HeaderMsg(), B::HeaderMsg()}); },
       StatusCode::INVALID_ARGUMENT, "sent twice"},
      {"train header only", [&] { return TrainStream(*server_->stub, {B::HeaderMsg()}); }, StatusCode::INVALID_ARGUMENT,
       "no clouds"},
      {"train an empty message", [&] { return TrainStream(*server_->stub, {B::HeaderMsg(), v1::TrainRequest()}); },
       StatusCode::INVALID_ARGUMENT, "empty Train message"},
      {"train one category",
       [&] {
         std::vector<v1::TrainRequest> msgs{B::HeaderMsg()};
         for (const TrainingCloud& lc : *train_)
           if (lc.category == "chair") msgs.push_back(CloudMessage(lc));
         return TrainStream(*server_->stub, msgs);
       },
       StatusCode::FAILED_PRECONDITION, "2 categories"},
      {"train empty category name", [&] { return TrainStream(*server_->stub, B::TrainWith("", {Noise(500, 0.3f)})); },
       StatusCode::INVALID_ARGUMENT, "empty category"},
      {"train a category of empty clouds",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {Cloud{}, Cloud{}})); },
       StatusCode::INVALID_ARGUMENT, "category 'table', object 'table0'): the cloud is empty"},
      {"train a category of one-point clouds",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {Same(1), Same(1)})); },
       StatusCode::INVALID_ARGUMENT, "1 usable point after"},
      {"train a category of collinear clouds",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {Line(2000), Line(1500)})); },
       StatusCode::INVALID_ARGUMENT, "collinear"},
      {"train a NaN cloud",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {With(Noise(500, 0.3f), 4, Vec3(0, kNaN, 0))})); },
       StatusCode::INVALID_ARGUMENT, "xyz: point 4 is not finite"},
      {"train a cloud at 1e30 m",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {Noise(500, 1e30f)})); },
       StatusCode::INVALID_ARGUMENT, "beyond +-1e6 m"},
      {"train 41 clouds (limit 40)",
       [&] {
         auto msgs = B::GoodTrain();
         while (msgs.size() < 42) msgs.push_back(CloudMessage(train_->at(0)));
         return TrainStream(*server_->stub, msgs);
       },
       StatusCode::RESOURCE_EXHAUSTED, "more than 40 training clouds"},
      {"train a cloud of 50001 points",
       [&] { return TrainStream(*server_->stub, B::TrainWith("table", {Noise(50'001, 0.3f)})); },
       StatusCode::RESOURCE_EXHAUSTED, "the limit is 50000"},
      {"train bad model name",
       [&] { return TrainStream(*server_->stub, B::GoodTrain([](v1::TrainHeader& h) { h.set_model_name("a b"); })); },
       StatusCode::INVALID_ARGUMENT, "may only contain"},
      {"train unknown method",
       [&] {
         return TrainStream(*server_->stub,
                            B::GoodTrain([](v1::TrainHeader& h) { h.add_methods(static_cast<v1::Method>(17)); }));
       },
       StatusCode::INVALID_ARGUMENT, "unknown method 17"},
      {"train default method not trained",
       [&] {
         return TrainStream(*server_->stub, B::GoodTrain([](v1::TrainHeader& h) {
                              h.add_methods(v1::METHOD_ESF);
                              h.set_default_method(v1::METHOD_BOK);
                            }));
       },
       StatusCode::INVALID_ARGUMENT, "default_method is not one of the methods"},
      {"train codebook of size 0",
       [&] {
         return TrainStream(*server_->stub,
                            B::GoodTrain([](v1::TrainHeader& h) { h.mutable_parameters()->set_bok_codebook_size(0); }));
       },
       StatusCode::INVALID_ARGUMENT, "bok_codebook_size must be positive"},
      {"train NaN support radius",
       [&] {
         return TrainStream(*server_->stub,
                            B::GoodTrain([](v1::TrainHeader& h) { h.mutable_parameters()->set_support_radius_m(NAN); }));
       },
       StatusCode::INVALID_ARGUMENT, "support_radius_m"},
      {"train a 5000-byte description",
       [&] {
         return TrainStream(*server_->stub,
                            B::GoodTrain([](v1::TrainHeader& h) { h.set_description(std::string(5000, 'd')); }));
       },
       StatusCode::INVALID_ARGUMENT, "description is longer"},
      // ---- StreamClassify: message order and content
      {"stream first chunk without a model", [&] { return B::Stream({B::Chunk(good)}); }, StatusCode::INVALID_ARGUMENT,
       "model name is empty"},
      {"stream unknown model", [&] { return B::Stream({B::Chunk(good, "no-such-model")}); }, StatusCode::NOT_FOUND,
       "no-such-model"},
      {"stream second chunk names another model",
       [&] { return B::Stream({B::Chunk(Cloud{}, "zoo"), B::Chunk(good, "zoo-esf")}); }, StatusCode::INVALID_ARGUMENT,
       "only the first chunk chooses"},
      {"stream second chunk names another method",
       [&] {
         auto second = B::Chunk(good);
         second.set_method(v1::METHOD_BOK);
         return B::Stream({B::Chunk(Cloud{}, "zoo"), second});
       },
       StatusCode::INVALID_ARGUMENT, "only the first chunk chooses"},
      {"stream unknown method",
       [&] {
         auto first = B::Chunk(good, "zoo");
         first.set_method(static_cast<v1::Method>(42));
         return B::Stream({first});
       },
       StatusCode::INVALID_ARGUMENT, "unknown method 42"},
      {"stream NaN in chunk 1",
       [&] { return B::Stream({B::Chunk(Cloud{}, "zoo"), B::Chunk(With(good, 7, Vec3(kNaN, 1, 1)))}); },
       StatusCode::INVALID_ARGUMENT, "chunk 1: xyz: point 7 is not finite"},
      {"stream chunk at 1e30 m", [&] { return B::Stream({B::Chunk(Noise(300, 1e30f), "zoo")}); },
       StatusCode::INVALID_ARGUMENT, "chunk 0: xyz: point 0 has a coordinate beyond"},
      {"stream chunk of 50001 points", [&] { return B::Stream({B::Chunk(Noise(50'001, 0.3f), "zoo")}); },
       StatusCode::RESOURCE_EXHAUSTED, "the limit is 50000"},
      {"stream past 20000 session points",
       [&] {
         std::vector<v1::ScanChunk> chunks;
         for (unsigned k = 0; k < 5; ++k) chunks.push_back(B::Chunk(Noise(6000, 0.3f, float(k), k), k ? "" : "zoo"));
         return B::Stream(chunks);
       },
       StatusCode::RESOURCE_EXHAUSTED, "20000"},
      // Every chunk is answered (undecided); the scan's end is an error, as Classify's of such a cloud.
      {"stream collinear chunks (never decided)", [&] { return B::Stream(B::Chunks(Line(2000), 4)); },
       StatusCode::INVALID_ARGUMENT, "the scan ended without a decision: its 2000 points"},
      {"stream copies of one point (never decided)", [&] { return B::Stream(B::Chunks(Same(2000), 4)); },
       StatusCode::INVALID_ARGUMENT, "the scan ended without a decision: its 1 point gave"},
      {"stream a model name only, no points", [&] { return B::Stream({B::Chunk(Cloud{}, "zoo")}); },
       StatusCode::INVALID_ARGUMENT, "the scan ended without a decision: its 0 points"},
      {"stream beyond --max-streams (4)",
       [&] {
         std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
         std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::ScanChunk, v1::Decision>>> open;
         for (int i = 0; i < 4; ++i) {  // hold every slot
           contexts.push_back(std::make_unique<grpc::ClientContext>());
           open.push_back(server_->stub->StreamClassify(contexts.back().get()));
           v1::Decision d;
           if (!open.back()->Write(B::Chunk(Cloud{}, "zoo")) || !open.back()->Read(&d))
             return grpc::Status(StatusCode::INTERNAL, "could not open stream " + std::to_string(i));
         }
         grpc::Status fifth = B::Stream({B::Chunk(good, "zoo")});
         for (auto& s : open) {
           s->WritesDone();
           for (v1::Decision rest; s->Read(&rest);) {}
           s->Finish();
         }
         return fifth;
       },
       StatusCode::RESOURCE_EXHAUSTED, "too many concurrent streams (limit 4)"},
      // ---- model management
      {"get unknown model",
       [&] {
         grpc::ClientContext ctx;
         v1::GetModelRequest req;
         req.mutable_model()->set_name("ghost");
         v1::ModelInfo info;
         return server_->stub->GetModel(&ctx, req, &info);
       },
       StatusCode::NOT_FOUND, "ghost"},
      {"delete unknown version",
       [&] {
         grpc::ClientContext ctx;
         v1::DeleteModelRequest req;
         req.set_name("zoo");
         req.set_version(9);
         v1::DeleteModelResponse resp;
         return server_->stub->DeleteModel(&ctx, req, &resp);
       },
       StatusCode::NOT_FOUND, "9"},
      {"set-default unknown version",
       [&] {
         grpc::ClientContext ctx;
         v1::SetDefaultModelRequest req;
         req.set_name("zoo");
         req.set_version(9);
         v1::ModelInfo info;
         return server_->stub->SetDefaultModel(&ctx, req, &info);
       },
       StatusCode::NOT_FOUND, "9"},
      {"list with a bad name",
       [&] {
         grpc::ClientContext ctx;
         v1::ListModelsRequest req;
         req.set_name(std::string(200, 'n'));
         v1::ListModelsResponse resp;
         return server_->stub->ListModels(&ctx, req, &resp);
       },
       StatusCode::INVALID_ARGUMENT, "longer than 128"},
  };

  const size_t stored = server_->store->List()->size();
  std::printf("%-52s %-20s %8s  %s\n", "case", "status", "ms", "message");
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    const auto t0 = std::chrono::steady_clock::now();
    const grpc::Status s = row.call();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%-52s %-20s %8.1f  %s\n", row.name.c_str(), CodeName(s.error_code()), ms,
                s.error_message().substr(0, 110).c_str());
    EXPECT_EQ(CodeName(s.error_code()), std::string(CodeName(row.code))) << s.error_message();
    EXPECT_THAT(s.error_message(), ::testing::HasSubstr(row.message));

    // The server keeps serving, answers a good view exactly as before and stored nothing new.
    EXPECT_EQ(HealthStatus(server_->channel), 1);
    v1::ClassifyResponse again;
    grpc::Status ok = Classify(*good_, "zoo", &again);
    ASSERT_TRUE(ok.ok()) << ok.error_message();
    EXPECT_EQ(again.winner(), reference_->winner());
    ASSERT_EQ(again.scores_size(), reference_->scores_size());
    for (int i = 0; i < again.scores_size(); ++i) EXPECT_EQ(again.scores(i).score(), reference_->scores(i).score());
    EXPECT_EQ(server_->store->List()->size(), stored);
  }
  for (int i = 0; i < 200 && server_->service->streams().active() > 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(server_->service->streams().active(), 0u);
  EXPECT_EQ(server_->metrics.ActiveStreams("StreamClassify"), 0);
  EXPECT_EQ(server_->metrics.ActiveStreams("Train"), 0);
  // Every bad request was answered by the service with a status, never INTERNAL or UNKNOWN.
  for (const server::RequestLog& l : server_->Logs()) {
    EXPECT_NE(l.code, "INTERNAL") << l.rpc << " " << l.message;
    EXPECT_NE(l.code, "UNKNOWN") << l.rpc << " " << l.message;
  }
}

}  // namespace
}  // namespace glimpse::reliability
