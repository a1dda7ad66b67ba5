// GlimpseService over an in-process channel with the fake engine: every RPC's success path, each
// status code, the stream limits, metrics and logs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fakes.h"

namespace glimpse::server {
namespace {

using ::testing::HasSubstr;
using testing::Harness;
using testing::SpiralCloud;

v1::ClassifyRequest ClassifyReq(const std::string& model, size_t points, uint32_t version = 0) {
  v1::ClassifyRequest req;
  req.mutable_model()->set_name(model);
  req.mutable_model()->set_version(version);
  *req.mutable_cloud() = wire::CloudToProto(SpiralCloud(points));
  return req;
}

grpc::Status Classify(Harness& h, const v1::ClassifyRequest& req, v1::ClassifyResponse* resp = nullptr) {
  grpc::ClientContext ctx;
  v1::ClassifyResponse local;
  return h.stub->Classify(&ctx, req, resp ? resp : &local);
}

// Polls `done` until it holds or a generous deadline passes (a loaded CI machine may take seconds).
template <class Done>
bool WaitUntil(Done done, std::chrono::seconds deadline = std::chrono::seconds(60)) {
  const auto end = std::chrono::steady_clock::now() + deadline;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// Waits until the server has logged `n` requests: a handler may still be finishing after its client
// has the status.
std::vector<RequestLog> WaitForLogs(Harness& h, size_t n) {
  WaitUntil([&] { return h.Logs().size() >= n; });
  return h.Logs();
}

// ---------------------------------------------------------------------------------------------
// Train

TEST(Train, StreamsProgressAndEndsWithTheStoredModel) {
  Harness h;
  v1::TrainProgress last;
  grpc::ClientContext ctx;
  auto stream = h.stub->Train(&ctx);
  v1::TrainRequest header;
  header.mutable_header()->set_model_name("shapes");
  header.mutable_header()->set_description("spheres vs boxes");
  header.mutable_header()->mutable_parameters()->set_bok_codebook_size(12);
  header.mutable_header()->mutable_parameters()->set_seed(7);
  ASSERT_TRUE(stream->Write(header));
  const size_t n = 300;
  for (size_t i = 0; i < n; ++i) {
    v1::TrainRequest req;
    req.mutable_cloud()->set_category(i % 3 == 0 ? "box" : "sphere");
    req.mutable_cloud()->set_object_id("obj" + std::to_string(i % 10));
    req.mutable_cloud()->set_augmented(i % 5 == 4);  // a simulated sensor's view: reaches the engine marked
    *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(20));
    ASSERT_TRUE(stream->Write(req));
  }
  stream->WritesDone();
  std::vector<v1::TrainProgress> progress;
  for (v1::TrainProgress p; stream->Read(&p);) progress.push_back(p);
  ASSERT_TRUE(stream->Finish().ok());

  ASSERT_GE(progress.size(), 3u);
  EXPECT_EQ(progress.front().stage(), "received");
  EXPECT_EQ(progress.front().clouds_received(), n);
  EXPECT_EQ(progress.front().percent(), 0);
  double percent = 0;
  for (const auto& p : progress) {
    EXPECT_GE(p.percent(), percent);
    percent = p.percent();
  }
  const v1::TrainProgress& done = progress.back();
  EXPECT_EQ(done.stage(), "done");
  EXPECT_EQ(done.percent(), 100);
  EXPECT_EQ(done.clouds_received(), n);
  EXPECT_EQ(h.behaviour.augmented_clouds, int(n / 5));
  EXPECT_EQ(done.features_extracted(), n);
  EXPECT_EQ(done.codebooks_fitted(), 1u);
  const v1::ModelInfo& m = done.model();
  EXPECT_GT(m.id(), 0u);
  EXPECT_EQ(m.name(), "shapes");
  EXPECT_EQ(m.version(), 1u);
  EXPECT_TRUE(m.is_default());
  EXPECT_EQ(m.description(), "spheres vs boxes");
  EXPECT_THAT(m.categories(), ::testing::ElementsAre("box", "sphere"));
  EXPECT_EQ(m.stats().clouds(), n);
  EXPECT_EQ(m.stats().objects(), 10u);
  ASSERT_EQ(m.stats().categories_size(), 2);
  EXPECT_EQ(m.stats().categories(0).clouds(), 100u);
  EXPECT_EQ(m.parameters().bok_codebook_size(), 12u);
  EXPECT_EQ(m.parameters().seed(), 7u);
  EXPECT_FALSE(m.parameters().has_bog_pca_dims());
  EXPECT_GT(m.size_bytes(), 0u);
  EXPECT_EQ(m.sha256().size(), 64u);

  v1::TrainProgress again;
  ASSERT_TRUE(h.Train("shapes", {"a", "b"}, &again).ok());
  EXPECT_EQ(again.model().version(), 2u);
}

TEST(Train, RejectsBadStreamsWithInvalidArgumentAndStoresNothing) {
  Harness h;
  auto run = [&](const std::vector<v1::TrainRequest>& msgs) {
    grpc::ClientContext ctx;
    auto stream = h.stub->Train(&ctx);
    for (const auto& m : msgs) stream->Write(m);
    stream->WritesDone();
    for (v1::TrainProgress p; stream->Read(&p);) {
    }
    return stream->Finish();
  };
  v1::TrainRequest header, cloud, unlabelled, nan;
  header.mutable_header()->set_model_name("m");
  cloud.mutable_cloud()->set_category("box");
  *cloud.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(10));
  unlabelled = cloud;
  unlabelled.mutable_cloud()->clear_category();
  nan = cloud;
  Cloud bad = SpiralCloud(10);
  bad.points[4].x() = std::nanf("");
  *nan.mutable_cloud()->mutable_cloud() = wire::CloudToProto(bad);
  v1::TrainRequest bad_name = header;
  bad_name.mutable_header()->set_model_name("no spaces");

  EXPECT_EQ(run({cloud}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);           // no header
  EXPECT_EQ(run({header, header}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);  // two headers
  EXPECT_EQ(run({header}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);          // no clouds
  EXPECT_EQ(run({}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(run({bad_name, cloud}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(run({header, cloud, unlabelled}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  grpc::Status s = run({header, cloud, nan});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("cloud 1: xyz: point 4 is not finite"));
  EXPECT_TRUE(h.store->List()->empty());
}

TEST(Train, SingleCategoryIsFailedPreconditionAsTheProtoSays) {
  Harness h;
  v1::TrainProgress last;
  grpc::Status s = h.Train("m", {"only"}, &last, 3);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("2 categories"));
  EXPECT_TRUE(h.store->List()->empty());
}

TEST(Train, LimitsAreResourceExhausted) {
  Limits limits;
  limits.max_train_clouds = 3;
  Harness h(limits);
  v1::TrainProgress last;
  grpc::Status s = h.Train("m", {"a", "b"}, &last, 2);  // 4 clouds
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_TRUE(h.store->List()->empty());
}

TEST(Train, CoreErrorsMapThroughToGrpcStatus) {
  Harness h;
  v1::TrainProgress last;
  h.behaviour.train_error = failed_precondition("a category has no keypoints");
  grpc::Status s = h.Train("m", {"a", "b"}, &last);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(s.error_message(), "a category has no keypoints");
  h.behaviour.train_error = internal_error("k-means diverged");
  EXPECT_EQ(h.Train("m", {"a", "b"}, &last).error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_TRUE(h.store->List()->empty());
}

// A model stored becomes its name's default: one that would not read back (codebook sizes the reader
// refuses) would break every Classify of the name, so Train reads it back first and stores nothing.
TEST(Train, AModelThatDoesNotReadBackIsNotStored) {
  Harness h;
  v1::TrainProgress last;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &last).ok());
  h.behaviour.deserialize_error = data_loss("corrupt model: codebook sizes out of range");
  const grpc::Status s = h.Train("m", {"a", "b"}, &last);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_NE(s.error_message().find("does not read back"), std::string::npos) << s.error_message();
  EXPECT_NE(s.error_message().find("nothing was stored"), std::string::npos) << s.error_message();
  h.behaviour.deserialize_error.reset();
  EXPECT_EQ(h.store->List()->size(), 1u);
  v1::ClassifyResponse r;
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10), &r).ok());
  EXPECT_EQ(r.model().version(), 1u);
}

TEST(Train, DeadlineStopsTrainingAndStoresNothing) {
  Harness h;
  h.behaviour.train_waits_for_cancel = true;
  grpc::ClientContext ctx;
  // Long enough for the upload to reach training even under a sanitizer on a busy machine (at 300 ms
  // the deadline could pass before train started: right status, but not the case this test is about).
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1500));
  auto stream = h.stub->Train(&ctx);
  v1::TrainRequest header;
  header.mutable_header()->set_model_name("m");
  stream->Write(header);
  v1::TrainRequest cloud;
  cloud.mutable_cloud()->set_category("a");
  *cloud.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(10));
  stream->Write(cloud);
  stream->WritesDone();
  for (v1::TrainProgress p; stream->Read(&p);) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  auto logs = WaitForLogs(h, 1);
  ASSERT_EQ(logs.size(), 1u);
  EXPECT_EQ(logs[0].code, "DEADLINE_EXCEEDED");
  EXPECT_EQ(h.behaviour.train_calls, 1);
  EXPECT_TRUE(h.store->List()->empty());
}

TEST(Train, ClientCancelStopsTrainingAndStoresNothing) {
  Harness h;
  h.behaviour.train_waits_for_cancel = true;
  grpc::ClientContext ctx;
  auto stream = h.stub->Train(&ctx);
  v1::TrainRequest header;
  header.mutable_header()->set_model_name("m");
  stream->Write(header);
  v1::TrainRequest cloud;
  cloud.mutable_cloud()->set_category("a");
  *cloud.mutable_cloud()->mutable_cloud() = wire::CloudToProto(SpiralCloud(10));
  stream->Write(cloud);
  stream->WritesDone();
  v1::TrainProgress received;  // read, so the server's first write does not wait for this client
  ASSERT_TRUE(stream->Read(&received));
  EXPECT_EQ(received.stage(), "received");
  ASSERT_TRUE(WaitUntil([&] { return h.behaviour.train_calls > 0; }));
  ctx.TryCancel();
  for (v1::TrainProgress p; stream->Read(&p);) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  auto logs = WaitForLogs(h, 1);
  ASSERT_EQ(logs.size(), 1u);
  EXPECT_EQ(logs[0].code, "CANCELLED");
  EXPECT_TRUE(h.store->List()->empty());
}

// ---------------------------------------------------------------------------------------------
// Classify

TEST(Classify, ScoresEveryCategoryWithTheDefaultVersion) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("shapes", {"box", "cylinder", "sphere"}, &t).ok());
  v1::ClassifyResponse r;
  ASSERT_TRUE(Classify(h, ClassifyReq("shapes", 100), &r).ok());
  EXPECT_EQ(r.model().name(), "shapes");
  EXPECT_EQ(r.model().version(), 1u);
  EXPECT_EQ(r.model_id(), t.model().id());
  EXPECT_EQ(r.method(), v1::METHOD_FUSION);  // the fake's default
  ASSERT_EQ(r.scores_size(), 3);
  EXPECT_EQ(r.scores(0).category(), "box");
  EXPECT_EQ(r.scores(2).category(), "sphere");
  EXPECT_EQ(r.winner_index(), 100 % 3);
  EXPECT_EQ(r.winner(), "cylinder");
  EXPECT_DOUBLE_EQ(r.scores(1).score(), 0.7);
  EXPECT_EQ(r.points(), 100u);
  EXPECT_EQ(r.keypoints(), 10u);
  EXPECT_DOUBLE_EQ(r.timings().feature_ms(), 1.5);
  EXPECT_GE(r.timings().total_ms(), 0);
  EXPECT_GT(r.timings().model_load_ms(), 0);  // first use: deserialized

  v1::ClassifyResponse again;
  auto req = ClassifyReq("shapes", 100);
  req.set_method(v1::METHOD_BOK);
  ASSERT_TRUE(Classify(h, req, &again).ok());
  EXPECT_EQ(again.method(), v1::METHOD_BOK);
  EXPECT_EQ(again.timings().model_load_ms(), 0);  // cached
  EXPECT_EQ(h.behaviour.deserialize_calls, 2);  // Train read it back before storing it; the first Classify
}

TEST(Classify, NamedVersionAndSetDefaultChooseTheModel) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  ASSERT_TRUE(h.Train("m", {"a", "b", "c"}, &t).ok());
  v1::ClassifyResponse r;
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10), &r).ok());
  EXPECT_EQ(r.model().version(), 2u);
  EXPECT_EQ(r.scores_size(), 3);
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10, 1), &r).ok());
  EXPECT_EQ(r.model().version(), 1u);
  EXPECT_EQ(r.scores_size(), 2);

  grpc::ClientContext ctx;
  v1::SetDefaultModelRequest pin;
  pin.set_name("m");
  pin.set_version(1);
  v1::ModelInfo info;
  ASSERT_TRUE(h.stub->SetDefaultModel(&ctx, pin, &info).ok());
  EXPECT_EQ(info.version(), 1u);
  EXPECT_TRUE(info.is_default());
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10), &r).ok());
  EXPECT_EQ(r.model().version(), 1u);
}

TEST(Classify, InvalidArgument) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  auto code = [&](v1::ClassifyRequest req) { return Classify(h, req).error_code(); };
  auto req = ClassifyReq("m", 10);
  req.mutable_cloud()->mutable_xyz()->push_back('x');  // 121 bytes
  EXPECT_EQ(code(req), grpc::StatusCode::INVALID_ARGUMENT);
  Cloud bad = SpiralCloud(10);
  bad.points[6].z() = std::numeric_limits<float>::infinity();
  req = ClassifyReq("m", 10);
  *req.mutable_cloud() = wire::CloudToProto(bad);
  grpc::Status s = Classify(h, req);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("point 6"));
  req = ClassifyReq("m", 10);
  req.set_method(static_cast<v1::Method>(99));
  EXPECT_EQ(code(req), grpc::StatusCode::INVALID_ARGUMENT);
  req = ClassifyReq("m", 10);
  EXPECT_EQ(code(ClassifyReq("", 10)), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(code(ClassifyReq("m", 2)), grpc::StatusCode::INVALID_ARGUMENT);  // core: too few points
}

TEST(Classify, AMethodTheModelLacksIsFailedPrecondition) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());  // the fake trains bok and fusion
  auto req = ClassifyReq("m", 10);
  req.set_method(v1::METHOD_VFH);
  grpc::Status s = Classify(h, req);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("not trained"));
}

TEST(Classify, TheCoreWarningReachesTheResponse) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  v1::ClassifyResponse r;
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10), &r).ok());
  EXPECT_EQ(r.warning(), "");
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 5000), &r).ok());  // the fake warns from 5000 points on
  EXPECT_EQ(r.warning(), "the cloud is large");
}

// "None of these" travels as the engine decides it, at the request's operating point (the fake: novelty
// = points modulo 5, unknown above 2 by default, above 4 x known_acceptance when a request sets one).
TEST(Classify, UnknownAnswersCarryNoveltyReasonAndTheClosestCategory) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  v1::ClassifyResponse r;
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 13), &r).ok());  // novelty 3 > 2
  EXPECT_TRUE(r.unknown());
  ASSERT_TRUE(r.has_novelty());
  EXPECT_DOUBLE_EQ(r.novelty(), 3.0);
  EXPECT_THAT(r.unknown_reason(), HasSubstr("novelty 3"));
  EXPECT_EQ(r.winner(), "b");  // the nearest known category stays the winner
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 11), &r).ok());  // novelty 1
  EXPECT_FALSE(r.unknown());
  EXPECT_EQ(r.unknown_reason(), "");
  auto req = ClassifyReq("m", 13);
  req.set_known_acceptance(0.9);  // threshold 3.6: novelty 3 is accepted
  ASSERT_TRUE(Classify(h, req, &r).ok());
  EXPECT_FALSE(r.unknown());
  req.set_known_acceptance(0.25);  // threshold 1: novelty 3 is unknown
  ASSERT_TRUE(Classify(h, req, &r).ok());
  EXPECT_TRUE(r.unknown());
  for (double bad : {-0.5, 1.01, std::nan("")}) {
    req.set_known_acceptance(bad);
    grpc::Status s = Classify(h, req);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_THAT(s.error_message(), HasSubstr("known_acceptance"));
  }
}

TEST(Classify, NotFound) {
  Harness h;
  EXPECT_EQ(Classify(h, ClassifyReq("nobody", 10)).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  EXPECT_EQ(Classify(h, ClassifyReq("m", 10, 7)).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(Classify, TooManyPointsIsResourceExhausted) {
  Limits limits;
  limits.max_points_per_cloud = 100;
  Harness h(limits);
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());  // 50-61 points per cloud
  EXPECT_TRUE(Classify(h, ClassifyReq("m", 100)).ok());
  grpc::Status s = Classify(h, ClassifyReq("m", 101));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
}

TEST(Classify, CoreFailuresMapToTheirCodes) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  h.behaviour.classify_error = failed_precondition("the model is not trained");
  EXPECT_EQ(Classify(h, ClassifyReq("m", 10)).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  h.behaviour.classify_error = resource_exhausted("too many keypoints");
  EXPECT_EQ(Classify(h, ClassifyReq("m", 10)).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  h.behaviour.classify_error.reset();
  h.behaviour.classify_throws = true;  // no exception crosses the RPC
  grpc::Status s = Classify(h, ClassifyReq("m", 10));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_THAT(s.error_message(), HasSubstr("boom"));
}

TEST(Classify, CorruptStoredModelIsDataLoss) {
  Harness h;
  NewModel garbage;
  garbage.name = "broken";
  garbage.methods = {MethodId::kBoK};
  garbage.blob = {1, 2, 3};
  ASSERT_TRUE(h.store->Put(garbage).ok());
  EXPECT_EQ(Classify(h, ClassifyReq("broken", 10)).error_code(), grpc::StatusCode::DATA_LOSS);
}

TEST(Classify, DeadlineAlreadyPassedIsDeadlineExceeded) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() - std::chrono::seconds(1));
  v1::ClassifyResponse r;
  EXPECT_EQ(h.stub->Classify(&ctx, ClassifyReq("m", 10), &r).error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
}

// ---------------------------------------------------------------------------------------------
// StreamClassify

v1::ScanChunk Chunk(size_t points, const std::string& model = "", uint32_t version = 0) {
  v1::ScanChunk c;
  if (!model.empty()) {
    c.mutable_model()->set_name(model);
    c.mutable_model()->set_version(version);
  }
  if (points) *c.mutable_cloud() = wire::CloudToProto(SpiralCloud(points));
  return c;
}

TEST(StreamClassify, AnswersEveryChunkWithTheEvolvingDecision) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  grpc::ClientContext ctx;
  auto stream = h.stub->StreamClassify(&ctx);
  std::vector<v1::Decision> decisions;
  v1::Decision d;
  ASSERT_TRUE(stream->Write(Chunk(0, "m")));  // names the model only
  ASSERT_TRUE(stream->Read(&d));
  decisions.push_back(d);
  for (size_t points : {10u, 20u, 30u, 40u}) {
    ASSERT_TRUE(stream->Write(Chunk(points)));
    ASSERT_TRUE(stream->Read(&d));
    decisions.push_back(d);
  }
  stream->WritesDone();
  v1::Decision final;
  ASSERT_TRUE(stream->Read(&final));  // the scan is over: the session's final decision
  EXPECT_FALSE(stream->Read(&d));
  ASSERT_TRUE(stream->Finish().ok());
  EXPECT_TRUE(final.final());
  EXPECT_FALSE(decisions.back().final());
  EXPECT_EQ(final.chunk_index(), decisions.back().chunk_index());
  EXPECT_EQ(final.points(), 100u);
  EXPECT_EQ(final.raw_scores_size(), 2);
  EXPECT_EQ(final.model().name(), "m");

  EXPECT_EQ(decisions[0].winner_index(), -1);
  EXPECT_EQ(decisions[0].winner(), "");
  EXPECT_EQ(decisions[0].model().version(), 1u);
  EXPECT_EQ(decisions[0].method(), v1::METHOD_FUSION);
  for (size_t i = 0; i < decisions.size(); ++i) EXPECT_EQ(decisions[i].chunk_index(), i);  // the message answered
  for (size_t i = 1; i < decisions.size(); ++i) {
    EXPECT_EQ(decisions[i].scores_size(), 2);
    EXPECT_EQ(decisions[i].model().name(), "m");
  }
  EXPECT_EQ(decisions[4].points(), 100u);  // accumulated
  EXPECT_EQ(decisions[4].winner(), "a");   // 100 % 2
  EXPECT_EQ(decisions[1].winner(), "a");   // 10, 30, 60, 100: all even
  EXPECT_TRUE(decisions[4].settled());
  EXPECT_EQ(h.metrics.ActiveStreams("StreamClassify"), 0);
}

TEST(StreamClassify, DecisionsCarryUnknownAtTheStreamsOperatingPoint) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  for (double acceptance : {0.0, 0.9}) {
    grpc::ClientContext ctx;
    auto stream = h.stub->StreamClassify(&ctx);
    v1::ScanChunk first = Chunk(0, "m");
    first.set_known_acceptance(acceptance);
    ASSERT_TRUE(stream->Write(first));
    v1::Decision d;
    ASSERT_TRUE(stream->Read(&d));
    std::vector<v1::Decision> decisions;
    for (size_t points : {11u, 2u}) {  // 11 points: novelty 1; 13: novelty 3
      v1::ScanChunk c = Chunk(points);
      c.set_known_acceptance(acceptance);  // repeating the first chunk's is allowed
      ASSERT_TRUE(stream->Write(c));
      ASSERT_TRUE(stream->Read(&d));
      decisions.push_back(d);
    }
    stream->WritesDone();
    ASSERT_TRUE(stream->Read(&d));
    EXPECT_TRUE(d.final());
    ASSERT_TRUE(stream->Finish().ok());
    EXPECT_FALSE(decisions[0].unknown());
    EXPECT_DOUBLE_EQ(decisions[0].novelty(), 1.0);
    EXPECT_EQ(decisions[1].unknown(), acceptance == 0.0) << acceptance;  // 3 > 2, but not > 3.6
    EXPECT_DOUBLE_EQ(decisions[1].novelty(), 3.0);
    EXPECT_EQ(decisions[1].winner(), "b");
    if (acceptance == 0.0) {
      EXPECT_THAT(decisions[1].unknown_reason(), HasSubstr("novelty 3"));
    }
  }
  // Only the first chunk sets the operating point; a bad one is refused.
  for (double bad : {1.5, -1.0}) {
    grpc::ClientContext ctx;
    auto stream = h.stub->StreamClassify(&ctx);
    v1::ScanChunk first = Chunk(10, "m");
    first.set_known_acceptance(bad);
    stream->Write(first);
    stream->WritesDone();
    v1::Decision d;
    EXPECT_FALSE(stream->Read(&d));
    grpc::Status s = stream->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(s.error_message(), HasSubstr("known_acceptance"));
  }
  grpc::ClientContext ctx;
  auto stream = h.stub->StreamClassify(&ctx);
  ASSERT_TRUE(stream->Write(Chunk(10, "m")));
  v1::Decision d;
  ASSERT_TRUE(stream->Read(&d));
  v1::ScanChunk later = Chunk(10);
  later.set_known_acceptance(0.5);
  stream->Write(later);
  stream->WritesDone();
  while (stream->Read(&d)) {
  }
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("known acceptance"));
}

TEST(StreamClassify, Errors) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  ASSERT_TRUE(h.Train("other", {"a", "b"}, &t).ok());
  auto run = [&](std::vector<v1::ScanChunk> chunks) {
    grpc::ClientContext ctx;
    auto stream = h.stub->StreamClassify(&ctx);
    for (const auto& c : chunks) {
      if (!stream->Write(c)) break;
      v1::Decision d;
      if (!stream->Read(&d)) break;
    }
    stream->WritesDone();
    for (v1::Decision d; stream->Read(&d);) {}
    return stream->Finish();
  };
  EXPECT_EQ(run({Chunk(10, "nope")}).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(run({Chunk(10)}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);  // no model named
  EXPECT_EQ(run({Chunk(10, "m"), Chunk(10, "other")}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(run({Chunk(10, "m"), Chunk(10, "m", 1)}).ok());  // repeating it is fine
  // A scan that ends with nothing decided is an error, as Classify's of too few points is.
  const grpc::Status undecided = run({Chunk(0, "m")});
  EXPECT_EQ(undecided.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(undecided.error_message().find("the scan ended without a decision: its 0 points"), std::string::npos)
      << undecided.error_message();
  // So is a stream closed before its first chunk.
  const grpc::Status nothing = run({});
  EXPECT_EQ(nothing.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(nothing.error_message().find("before its first chunk"), std::string::npos) << nothing.error_message();
  v1::ScanChunk nan = Chunk(10, "m");
  nan.mutable_cloud()->mutable_xyz()->resize(13);
  EXPECT_EQ(run({nan}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  h.behaviour.session_error = resource_exhausted("the session holds 1000000 points");
  EXPECT_EQ(run({Chunk(10, "m")}).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(h.metrics.ActiveStreams("StreamClassify"), 0);
}

TEST(StreamClassify, ConcurrentStreamsBeyondTheLimitAreResourceExhausted) {
  Limits limits;
  limits.max_concurrent_streams = 1;
  Harness h(limits);
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());

  grpc::ClientContext first_ctx;
  auto first = h.stub->StreamClassify(&first_ctx);
  v1::Decision d;
  ASSERT_TRUE(first->Write(Chunk(10, "m")));
  ASSERT_TRUE(first->Read(&d));  // the first stream holds the only slot
  EXPECT_EQ(h.metrics.ActiveStreams("StreamClassify"), 1);

  grpc::ClientContext second_ctx;
  auto second = h.stub->StreamClassify(&second_ctx);
  second->Write(Chunk(10, "m"));
  EXPECT_FALSE(second->Read(&d));
  grpc::Status s = second->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("concurrent streams"));
  v1::TrainProgress rejected;  // Train shares the limit
  EXPECT_EQ(h.Train("m", {"a", "b"}, &rejected).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);

  first->WritesDone();
  while (first->Read(&d)) {}
  ASSERT_TRUE(first->Finish().ok());
  ASSERT_TRUE(WaitUntil([&] { return h.service->streams().active() == 0; })) << "the first stream's slot was never freed";
  grpc::ClientContext third_ctx;
  auto third = h.stub->StreamClassify(&third_ctx);
  ASSERT_TRUE(third->Write(Chunk(10, "m")));
  EXPECT_TRUE(third->Read(&d));
  third->WritesDone();
  while (third->Read(&d)) {}
  EXPECT_TRUE(third->Finish().ok());
}

struct FakeClock {
  std::atomic<int64_t> offset_s{0};
  std::chrono::steady_clock::time_point base = std::chrono::steady_clock::now();
  SteadyClock fn() {
    return [this] { return base + std::chrono::seconds(offset_s.load()); };
  }
};

TEST(StreamClassify, StreamPastTheDurationLimitIsResourceExhausted) {
  FakeClock clock;
  Limits limits;
  limits.max_stream_duration = std::chrono::seconds(60);
  Harness h(limits, [&](ServiceOptions& o) { o.clock = clock.fn(); });
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  grpc::ClientContext ctx;
  auto stream = h.stub->StreamClassify(&ctx);
  v1::Decision d;
  ASSERT_TRUE(stream->Write(Chunk(10, "m")));
  ASSERT_TRUE(stream->Read(&d));
  clock.offset_s = 61;
  stream->Write(Chunk(10));
  EXPECT_FALSE(stream->Read(&d));
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("60 s"));
}

TEST(StreamClassify, IdleStreamPastTheLimitIsCancelledByTheWatchdog) {
  FakeClock clock;
  Limits limits;
  limits.max_stream_duration = std::chrono::seconds(60);
  Harness h(limits, [&](ServiceOptions& o) { o.clock = clock.fn(); });
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  const size_t logs_before = h.Logs().size();
  grpc::ClientContext ctx;
  auto stream = h.stub->StreamClassify(&ctx);
  v1::Decision d;
  ASSERT_TRUE(stream->Write(Chunk(10, "m")));
  ASSERT_TRUE(stream->Read(&d));
  EXPECT_EQ(h.service->streams().Reap(), 0u);  // young
  clock.offset_s = 61;
  EXPECT_EQ(h.service->streams().Reap(), 1u);
  EXPECT_FALSE(stream->Read(&d));
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);  // all a cancelled client learns
  auto logs = WaitForLogs(h, logs_before + 1);
  ASSERT_EQ(logs.size(), logs_before + 1);
  EXPECT_EQ(logs.back().code, "RESOURCE_EXHAUSTED");  // the server knows why
}

// ---------------------------------------------------------------------------------------------
// Model management

TEST(Models, ListGetDeleteSetDefault) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("chairs", {"a", "b"}, &t, 2, [](v1::TrainHeader& hd) {
    hd.add_methods(v1::METHOD_BOK);
    hd.add_methods(v1::METHOD_KGH);
    hd.set_default_method(v1::METHOD_KGH);
    hd.mutable_parameters()->set_support_radius_m(0.04);
  }).ok());
  ASSERT_TRUE(h.Train("chairs", {"a", "b"}, &t).ok());
  ASSERT_TRUE(h.Train("tables", {"x", "y"}, &t).ok());

  {
    grpc::ClientContext ctx;
    v1::ListModelsResponse all;
    ASSERT_TRUE(h.stub->ListModels(&ctx, v1::ListModelsRequest(), &all).ok());
    ASSERT_EQ(all.models_size(), 3);
    EXPECT_EQ(all.models(0).name(), "chairs");
    EXPECT_FALSE(all.models(0).is_default());
    EXPECT_TRUE(all.models(1).is_default());
    EXPECT_EQ(all.models(2).name(), "tables");
  }
  {
    grpc::ClientContext ctx;
    v1::ListModelsRequest req;
    req.set_name("tables");
    v1::ListModelsResponse some;
    ASSERT_TRUE(h.stub->ListModels(&ctx, req, &some).ok());
    EXPECT_EQ(some.models_size(), 1);
  }
  {
    grpc::ClientContext ctx;
    v1::GetModelRequest req;
    req.mutable_model()->set_name("chairs");
    req.mutable_model()->set_version(1);
    v1::ModelInfo info;
    ASSERT_TRUE(h.stub->GetModel(&ctx, req, &info).ok());
    EXPECT_EQ(info.version(), 1u);
    EXPECT_THAT(info.methods(), ::testing::ElementsAre(v1::METHOD_BOK, v1::METHOD_KGH));
    EXPECT_EQ(info.default_method(), v1::METHOD_KGH);
    EXPECT_DOUBLE_EQ(info.parameters().support_radius_m(), 0.04);
    EXPECT_THAT(info.categories(), ::testing::ElementsAre("a", "b"));
    EXPECT_EQ(info.stats().clouds(), 4u);
    EXPECT_GT(info.created().seconds(), 1'600'000'000);
  }
  {
    grpc::ClientContext ctx;
    v1::SetDefaultModelRequest req;
    req.set_name("chairs");
    req.set_version(1);
    v1::ModelInfo info;
    ASSERT_TRUE(h.stub->SetDefaultModel(&ctx, req, &info).ok());
    EXPECT_TRUE(info.is_default());
  }
  {
    grpc::ClientContext ctx;
    v1::DeleteModelRequest req;
    req.set_name("chairs");
    req.set_version(1);
    v1::DeleteModelResponse resp;
    ASSERT_TRUE(h.stub->DeleteModel(&ctx, req, &resp).ok());
    EXPECT_THAT(resp.deleted_versions(), ::testing::ElementsAre(1u));
  }
  {
    grpc::ClientContext ctx;
    v1::GetModelRequest req;
    req.mutable_model()->set_name("chairs");
    v1::ModelInfo info;
    ASSERT_TRUE(h.stub->GetModel(&ctx, req, &info).ok());
    EXPECT_EQ(info.version(), 2u);  // the pin went with version 1
  }
  {
    grpc::ClientContext ctx;
    v1::DeleteModelRequest req;
    req.set_name("tables");
    v1::DeleteModelResponse resp;
    ASSERT_TRUE(h.stub->DeleteModel(&ctx, req, &resp).ok());
    EXPECT_THAT(resp.deleted_versions(), ::testing::ElementsAre(1u));
  }
  EXPECT_EQ(h.store->List()->size(), 1u);
}

TEST(Models, NotFoundAndInvalidNames) {
  Harness h;
  grpc::ClientContext c1, c2, c3, c4, c5;
  v1::GetModelRequest get;
  get.mutable_model()->set_name("ghost");
  v1::ModelInfo info;
  EXPECT_EQ(h.stub->GetModel(&c1, get, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::DeleteModelRequest del;
  del.set_name("ghost");
  v1::DeleteModelResponse dr;
  EXPECT_EQ(h.stub->DeleteModel(&c2, del, &dr).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::SetDefaultModelRequest pin;
  pin.set_name("ghost");
  pin.set_version(2);
  EXPECT_EQ(h.stub->SetDefaultModel(&c3, pin, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  pin.set_name("bad name!");
  EXPECT_EQ(h.stub->SetDefaultModel(&c4, pin, &info).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::ListModelsRequest list;
  list.set_name("bad/name");
  v1::ListModelsResponse lr;
  EXPECT_EQ(h.stub->ListModels(&c5, list, &lr).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST(Models, DeletedVersionLeavesTheCache) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10)).ok());
  EXPECT_EQ(h.service->cache().size(), 1u);
  EXPECT_EQ(h.metrics.ModelsLoaded(), 1);
  grpc::ClientContext ctx;
  v1::DeleteModelRequest del;
  del.set_name("m");
  v1::DeleteModelResponse dr;
  ASSERT_TRUE(h.stub->DeleteModel(&ctx, del, &dr).ok());
  EXPECT_EQ(h.service->cache().size(), 0u);
  EXPECT_EQ(Classify(h, ClassifyReq("m", 10)).error_code(), grpc::StatusCode::NOT_FOUND);
}

// ---------------------------------------------------------------------------------------------
// Metrics and logs

TEST(Observability, MetricsCountRequestsByMethodAndCode) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 10)).ok());
  ASSERT_TRUE(Classify(h, ClassifyReq("m", 12)).ok());
  EXPECT_FALSE(Classify(h, ClassifyReq("ghost", 10)).ok());
  EXPECT_EQ(h.metrics.RequestCount("Classify", grpc::StatusCode::OK), 2);
  EXPECT_EQ(h.metrics.RequestCount("Classify", grpc::StatusCode::NOT_FOUND), 1);
  EXPECT_EQ(h.metrics.RequestCount("Train", grpc::StatusCode::OK), 1);
  EXPECT_EQ(h.metrics.ActiveStreams("Train"), 0);
  // The text exposition has the families a dashboard needs.
  std::string text;
  for (const auto& family : h.metrics.registry()->Collect()) text += family.name + "\n";
  for (const char* name : {"glimpse_rpc_requests_total", "glimpse_rpc_errors_total", "glimpse_rpc_duration_seconds",
                           "glimpse_active_streams", "glimpse_models_loaded"})
    EXPECT_THAT(text, HasSubstr(name));
}

TEST(Observability, OneLogLinePerRequestWithoutCloudDataOrMetadata) {
  Harness h;
  v1::TrainProgress t;
  ASSERT_TRUE(h.Train("m", {"a", "b"}, &t).ok());
  grpc::ClientContext ctx;
  ctx.AddMetadata("authorization", "Bearer s3cret-token");
  auto req = ClassifyReq("m", 10);
  v1::ClassifyResponse r;
  ASSERT_TRUE(h.stub->Classify(&ctx, req, &r).ok());
  auto logs = WaitForLogs(h, 2);
  ASSERT_EQ(logs.size(), 2u);
  const RequestLog& c = logs[1];
  EXPECT_EQ(c.rpc, "Classify");
  EXPECT_EQ(c.model, "m@1");
  EXPECT_EQ(c.method, "fusion");
  EXPECT_EQ(c.points, 10u);
  EXPECT_EQ(c.code, "OK");
  const std::string line = FormatLogLine(c);
  EXPECT_THAT(line, ::testing::Not(HasSubstr("s3cret")));
  EXPECT_THAT(line, ::testing::Not(HasSubstr(req.cloud().xyz().substr(12, 12))));
  EXPECT_EQ(logs[0].rpc, "Train");
  EXPECT_EQ(logs[0].model, "m@1");
  EXPECT_EQ(logs[0].messages, 5u);  // header + 4 clouds
}

}  // namespace
}  // namespace glimpse::server
