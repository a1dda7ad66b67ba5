// The real recogniser behind gRPC: Train then Classify (and StreamClassify) over the service give
// exactly the scores of calling core directly with the same parameters. A tiny synthetic problem:
// partial views of spheres, boxes and cylinders of a few sizes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include <random>

#include "common/fast_training.h"
#include "fakes.h"
#include "shapes.h"
#include "glimpse/learning/train_params.h"
#include "proto/wire/methods.h"
#include "proto/wire/train_params.h"

namespace glimpse::server {
namespace {

using glimpse::testing::FastTrainHeader;
using testing::Dataset;
using testing::Sample;

class CoreEngineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new std::vector<TrainingCloud>(Dataset());
    auto spec = wire::TrainSpecFromProto(FastTrainHeader("shapes"));
    ASSERT_TRUE(spec.ok()) << spec.error().message;
    auto params = wire::ToTrainParams(*spec);
    ASSERT_TRUE(params.ok());
    auto model = glimpse::train(*data_, *params);
    ASSERT_TRUE(model.ok()) << model.error().message;
    direct_ = new std::shared_ptr<const Model>(std::make_shared<const Model>(std::move(*model)));
  }
  static void TearDownTestSuite() {
    delete data_;
    delete direct_;
  }

  void SetUp() override {
    ASSERT_TRUE(direct_ && *direct_) << "direct training failed";
    harness_ = std::make_unique<testing::Harness>(Limits{}, [](ServiceOptions& o) { o.engine = CoreEngine(); });
    grpc::ClientContext ctx;
    auto stream = harness_->stub->Train(&ctx);
    v1::TrainRequest header;
    *header.mutable_header() = FastTrainHeader("shapes");
    ASSERT_TRUE(stream->Write(header));
    for (const TrainingCloud& lc : *data_) {
      v1::TrainRequest req;
      req.mutable_cloud()->set_category(lc.category);
      req.mutable_cloud()->set_object_id(lc.object_id);
      *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(lc.cloud);
      ASSERT_TRUE(stream->Write(req));
    }
    stream->WritesDone();
    for (v1::TrainProgress p; stream->Read(&p);) {
      trained_ = p;
      stages_.push_back(p.stage());
    }
    grpc::Status s = stream->Finish();
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  static std::vector<TrainingCloud>* data_;
  static std::shared_ptr<const Model>* direct_;
  std::unique_ptr<testing::Harness> harness_;
  v1::TrainProgress trained_;
  std::vector<std::string> stages_;  // of every progress message, in order
};

std::vector<TrainingCloud>* CoreEngineTest::data_ = nullptr;
std::shared_ptr<const Model>* CoreEngineTest::direct_ = nullptr;

TEST_F(CoreEngineTest, TrainOverGrpcStoresWhatCoreTrains) {
  const Model& direct = **direct_;
  const v1::ModelInfo& m = trained_.model();
  EXPECT_EQ(trained_.stage(), "done");
  EXPECT_EQ(m.version(), 1u);
  EXPECT_THAT(m.categories(), ::testing::ElementsAre("box", "cylinder", "sphere"));
  EXPECT_EQ(m.categories_size(), int(direct.categories.size()));
  EXPECT_EQ(m.methods_size(), int(direct.methods.size()));
  EXPECT_EQ(m.default_method(), wire::MethodToProto(direct.default_method));
  EXPECT_EQ(m.stats().clouds(), 18u);
  EXPECT_EQ(m.stats().objects(), 9u);
  EXPECT_EQ(m.stats().keypoints(), direct.stats.keypoints);
  // The stored bytes are core's format: they load, and hold the same model (the bytes themselves
  // differ only in the training time they record, which the classification tests make up for).
  auto blob = harness_->store->Blob(int64_t(m.id()));
  ASSERT_TRUE(blob.ok());
  auto stored = glimpse::deserialize(*blob);
  ASSERT_TRUE(stored.ok()) << stored.error().message;
  EXPECT_EQ(stored->categories, direct.categories);
  EXPECT_EQ(stored->methods, direct.methods);
  EXPECT_EQ(stored->stats.clouds_per_category, direct.stats.clouds_per_category);
  EXPECT_EQ(stored->stats.keypoints, direct.stats.keypoints);
  EXPECT_EQ(blob->size(), glimpse::serialize(direct).size());
}

TEST_F(CoreEngineTest, ClassifyOverGrpcGivesExactlyCoresScores) {
  for (const char* category : {"box", "cylinder", "sphere"}) {
    const TrainingCloud test = Sample(category, 7, 3);  // an unseen object and view
    for (MethodId method : (*direct_)->methods) {
      auto direct = glimpse::classify(**direct_, test.cloud, method);
      ASSERT_TRUE(direct.ok()) << direct.error().message;
      grpc::ClientContext ctx;
      v1::ClassifyRequest req;
      req.mutable_model()->set_name("shapes");
      req.set_method(wire::MethodToProto(method));
      *req.mutable_cloud() = wire::CloudToProto(test.cloud);
      v1::ClassifyResponse resp;
      grpc::Status s = harness_->stub->Classify(&ctx, req, &resp);
      ASSERT_TRUE(s.ok()) << s.error_message();
      ASSERT_EQ(resp.scores_size(), int(direct->scores.size()));
      for (size_t i = 0; i < direct->scores.size(); ++i) {
        EXPECT_EQ(resp.scores(int(i)).category(), direct->categories[i]);
        EXPECT_EQ(resp.scores(int(i)).score(), direct->scores[i]) << category << " " << method_name(method);
      }
      EXPECT_EQ(resp.winner_index(), direct->winner);
      EXPECT_EQ(resp.method(), wire::MethodToProto(method));
      EXPECT_EQ(resp.points(), direct->points);
      EXPECT_EQ(resp.keypoints(), direct->keypoints);
      EXPECT_EQ(resp.unknown(), direct->unknown);
      EXPECT_EQ(resp.has_novelty(), std::isfinite(direct->novelty));
      if (resp.has_novelty()) {
        EXPECT_EQ(resp.novelty(), direct->novelty);
      }
      EXPECT_EQ(resp.unknown_reason(), direct->unknown_reason);
    }
  }
}

// A cloud sent with its camera's frame: the answer names the edges core finds cut, and a frame its
// edges cannot be found from (no sensor) is INVALID_ARGUMENT naming what is missing.
TEST_F(CoreEngineTest, ClassifyOverGrpcNamesTheEdgesTheCamerasFrameCuts) {
  TrainingCloud test = Sample("cylinder", 7, 3);
  ASSERT_TRUE(test.cloud.sensor.has_value());
  // A narrow camera looking at the object's centre: 0.9 m tall and 2 m away, it overflows 10 degrees.
  test.cloud.frame = CameraFrame{-*test.cloud.sensor, Vec3::UnitZ(), 10.f, 10.f};
  auto direct = glimpse::classify(**direct_, test.cloud);
  ASSERT_TRUE(direct.ok()) << direct.error().message;
  ASSERT_TRUE(direct->frame_cut.top && direct->frame_cut.bottom);
  grpc::ClientContext ctx;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("shapes");
  *req.mutable_cloud() = wire::CloudToProto(test.cloud);
  v1::ClassifyResponse resp;
  grpc::Status s = harness_->stub->Classify(&ctx, req, &resp);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(std::vector<std::string>(resp.frame_cut().begin(), resp.frame_cut().end()), frame_edges(direct->frame_cut));
  EXPECT_EQ(resp.winner_index(), direct->winner);

  grpc::ClientContext bad_ctx;
  req.mutable_cloud()->clear_sensor();
  grpc::Status bad = harness_->stub->Classify(&bad_ctx, req, &resp);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad.error_message().find("frame needs the sensor"), std::string::npos) << bad.error_message();
}

// "None of these" at a request's operating point is core's set_known_acceptance, over gRPC too; a model
// of the default method has a novelty for every answer, and a sheet of metal, never learnt, is unknown.
TEST_F(CoreEngineTest, KnownAcceptanceOverGrpcIsCoresOperatingPoint) {
  Cloud sheet;  // a 3 m x 3 m wavy sheet: nothing like a box, cylinder or sphere
  for (int i = 0; i < 80; ++i)
    for (int j = 0; j < 80; ++j)
      sheet.points.emplace_back(0.04f * float(i), 0.04f * float(j), 0.1f * std::sin(0.3f * float(i)));
  const TrainingCloud box = Sample("box", 7, 3);
  for (const Cloud* cloud : std::vector<const Cloud*>{&box.cloud, &sheet})
    for (double acceptance : {0.0, 0.5, 0.99}) {
      auto direct = glimpse::classify(**direct_, *cloud);
      ASSERT_TRUE(direct.ok()) << direct.error().message;
      ASSERT_TRUE(glimpse::set_known_acceptance(**direct_, *direct, acceptance).ok());
      grpc::ClientContext ctx;
      v1::ClassifyRequest req;
      req.mutable_model()->set_name("shapes");
      req.set_known_acceptance(acceptance);
      *req.mutable_cloud() = wire::CloudToProto(*cloud);
      v1::ClassifyResponse resp;
      grpc::Status s = harness_->stub->Classify(&ctx, req, &resp);
      ASSERT_TRUE(s.ok()) << s.error_message();
      ASSERT_TRUE(resp.has_novelty());
      EXPECT_EQ(resp.novelty(), direct->novelty);
      EXPECT_EQ(resp.unknown(), direct->unknown) << acceptance;
      EXPECT_EQ(resp.unknown_reason(), direct->unknown_reason);
      if (cloud == &sheet && acceptance == 0.0) {
        EXPECT_TRUE(resp.unknown()) << "novelty " << resp.novelty();
      }
    }
}

TEST_F(CoreEngineTest, StreamClassifyOverGrpcGivesExactlyTheSessionsDecisions) {
  const TrainingCloud scan = Sample("cylinder", 8, 5);
  auto session = ScanSession::create(*direct_, SessionParams{});
  ASSERT_TRUE(session.ok()) << session.error().message;
  grpc::ClientContext ctx;
  auto stream = harness_->stub->StreamClassify(&ctx);
  const size_t chunks = 4, per = (scan.cloud.points.size() + chunks - 1) / chunks;
  v1::Decision last;
  for (size_t c = 0; c < chunks; ++c) {
    Cloud chunk;
    for (size_t i = c * per; i < std::min(scan.cloud.points.size(), (c + 1) * per); ++i)
      chunk.points.push_back(scan.cloud.points[i]);
    auto direct = (*session)->add(chunk);
    v1::ScanChunk msg;
    if (c == 0) msg.mutable_model()->set_name("shapes");
    *msg.mutable_cloud() = wire::CloudToProto(chunk);
    ASSERT_TRUE(stream->Write(msg));
    ASSERT_TRUE(direct.ok()) << direct.error().message;
    v1::Decision d;
    ASSERT_TRUE(stream->Read(&d));
    last = d;
    EXPECT_EQ(d.chunk_index(), direct->chunk_index);
    EXPECT_EQ(d.points(), direct->points);
    EXPECT_EQ(d.keypoints(), direct->keypoints);
    EXPECT_EQ(d.winner_index(), direct->winner);
    EXPECT_EQ(d.settled(), direct->settled);
    EXPECT_EQ(d.confidence(), direct->confidence);
    EXPECT_EQ(int(d.category_changes()), direct->category_changes);
    ASSERT_EQ(d.scores_size(), int(direct->scores.size()));
    for (size_t i = 0; i < direct->scores.size(); ++i) EXPECT_EQ(d.scores(int(i)).score(), direct->scores[i]);
  }
  stream->WritesDone();
  // Then the final decision: the session's finish(), which is Classify's answer on the whole scan.
  v1::Decision final;
  ASSERT_TRUE(stream->Read(&final));
  EXPECT_TRUE(final.final());
  v1::Decision after;
  EXPECT_FALSE(stream->Read(&after));  // nothing after the final one
  EXPECT_TRUE(stream->Finish().ok());
  auto finished = (*session)->finish();
  ASSERT_TRUE(finished.ok());
  EXPECT_EQ(final.chunk_index(), chunks - 1);
  EXPECT_EQ(final.winner_index(), finished->winner);
  ASSERT_EQ(final.raw_scores_size(), int(finished->raw_scores.size()));
  for (size_t i = 0; i < finished->raw_scores.size(); ++i) EXPECT_EQ(final.raw_scores(int(i)).score(), finished->raw_scores[i]);
  grpc::ClientContext cctx;
  v1::ClassifyRequest whole;
  whole.mutable_model()->set_name("shapes");
  Cloud streamed;  // the points the chunks carried (no sensor)
  streamed.points = scan.cloud.points;
  *whole.mutable_cloud() = wire::CloudToProto(streamed);
  v1::ClassifyResponse classified;
  ASSERT_TRUE(harness_->stub->Classify(&cctx, whole, &classified).ok());
  EXPECT_EQ(final.winner(), classified.winner());
  ASSERT_EQ(final.scores_size(), classified.scores_size());
  for (int i = 0; i < classified.scores_size(); ++i) EXPECT_EQ(final.scores(i).score(), classified.scores(i).score());
  EXPECT_EQ(last.chunk_index(), chunks - 1);
  EXPECT_GE(last.winner_index(), 0);
  EXPECT_GT(last.points(), 0u);
  // Keypoints are detected only when the session's method uses them (the default, fusion of global
  // descriptors, does not).
  const MethodId m = (*direct_)->default_method;
  if (m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH) EXPECT_GT(last.keypoints(), 0u);
  else EXPECT_EQ(last.keypoints(), 0u);
}

TEST_F(CoreEngineTest, ProgressNamesOnlyTheDocumentedStagesAndEndsOnceWithDone) {
  const std::vector<std::string> documented = {"received", "features", "codebooks", "centres", "calibration", "storing", "done"};
  ASSERT_FALSE(stages_.empty());
  size_t last = 0;
  for (const std::string& stage : stages_) {
    const size_t at = size_t(std::find(documented.begin(), documented.end(), stage) - documented.begin());
    ASSERT_LT(at, documented.size()) << "undocumented stage " << stage;
    EXPECT_GE(at, last) << stage << " after " << documented[last];
    last = at;
  }
  EXPECT_EQ(std::count(stages_.begin(), stages_.end(), "done"), 1);
  EXPECT_EQ(stages_.back(), "done");
  EXPECT_GT(std::count(stages_.begin(), stages_.end(), "calibration"), 0);
}

TEST_F(CoreEngineTest, ModelInfoCarriesTheParametersUsedAndTheFeatureVersion) {
  const v1::ModelInfo& m = trained_.model();
  EXPECT_EQ(m.feature_version(), kFeaturePipelineVersion);
  const TrainParams defaults;
  const v1::TrainParameters& p = m.parameters();
  EXPECT_EQ(p.bok_codebook_size(), 6u);  // asked for
  EXPECT_EQ(p.seed(), 11u);
  ASSERT_TRUE(p.has_kgh_distance_bins());  // not asked for: the default that was used
  EXPECT_EQ(p.kgh_distance_bins(), uint32_t(defaults.kgh_distance_bins));
  EXPECT_EQ(p.neighbours(), uint32_t(defaults.decision.neighbours));
  EXPECT_EQ(p.decision(), v1::DECISION_KIND_NEAREST_REFERENCE);
  EXPECT_TRUE(p.has_support_radius_m());
  EXPECT_EQ(p.support_radius_m(), 0.0);  // automatic, from each cloud's density
  EXPECT_EQ(p.normalise_histograms(), defaults.normalise_histograms);
  EXPECT_GT(m.min_extent_m(), 0.f);
  EXPECT_GE(m.max_extent_m(), m.min_extent_m());
  EXPECT_FLOAT_EQ(m.max_extent_m(), (*direct_)->stats.max_extent_m);
  // What is stored is what GetModel and ListModels show.
  grpc::ClientContext ctx;
  v1::GetModelRequest get;
  get.mutable_model()->set_name("shapes");
  v1::ModelInfo info;
  ASSERT_TRUE(harness_->stub->GetModel(&ctx, get, &info).ok());
  EXPECT_EQ(info.parameters().kgh_distance_bins(), p.kgh_distance_bins());
  EXPECT_EQ(info.feature_version(), kFeaturePipelineVersion);
}

TEST_F(CoreEngineTest, ClassifyBatchGivesExactlyClassifysAnswers) {
  v1::ClassifyBatchRequest batch;
  batch.mutable_model()->set_name("shapes");
  std::vector<Cloud> clouds;
  for (const char* category : {"box", "cylinder", "sphere", "box"}) clouds.push_back(Sample(category, 9, 4).cloud);
  clouds.push_back(Cloud{{Vec3(0, 0, 0), Vec3(1, 0, 0)}, std::nullopt, {}});  // too few points: fails alone
  for (const Cloud& c : clouds) *batch.add_clouds() = wire::CloudToProto(c);
  grpc::ClientContext ctx;
  v1::ClassifyBatchResponse resp;
  ASSERT_TRUE(harness_->stub->ClassifyBatch(&ctx, batch, &resp).ok());
  ASSERT_EQ(resp.results_size(), 5);
  for (size_t i = 0; i + 1 < clouds.size(); ++i) {
    auto direct = glimpse::classify(**direct_, clouds[i]);
    ASSERT_TRUE(direct.ok());
    const v1::ClassifyResult& r = resp.results(int(i));
    ASSERT_EQ(r.code(), 0) << r.message();
    ASSERT_EQ(r.response().scores_size(), int(direct->scores.size()));
    for (size_t c = 0; c < direct->scores.size(); ++c) EXPECT_EQ(r.response().scores(int(c)).score(), direct->scores[c]);
    EXPECT_EQ(r.response().winner_index(), direct->winner);
  }
  EXPECT_EQ(resp.results(4).code(), int(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(resp.results(4).message(), ::testing::HasSubstr("cloud 4"));
}

TEST_F(CoreEngineTest, ThreadsPerRequestDoNotChangeTheAnswer) {
  const Cloud cloud = Sample("cylinder", 6, 2).cloud;
  auto reference = glimpse::classify(**direct_, cloud);
  ASSERT_TRUE(reference.ok());
  for (int threads : {1, 2, 3}) {
    const Engine e = CoreEngine(threads);
    auto one = e.classify(**direct_, cloud, std::nullopt, {});
    ASSERT_TRUE(one.ok());
    EXPECT_EQ(one->scores, reference->scores) << threads;
    const std::vector<Cloud> clouds(3, cloud);
    auto many = e.classify_batch(**direct_, clouds, std::nullopt, {});
    ASSERT_EQ(many.size(), 3u);
    for (const auto& r : many) {
      ASSERT_TRUE(r.ok());
      EXPECT_EQ(r->scores, reference->scores) << threads;
    }
  }
}

TEST(CoreEngine, AModelOfAnotherFeatureVersionIsRefusedWithFailedPrecondition) {
  testing::Harness h(Limits{}, [](ServiceOptions& o) { o.engine = CoreEngine(); });
  TrainParams params;
  params.methods = {MethodId::kUSH};
  params.default_method = MethodId::kUSH;
  params.partial_prefixes.clear();
  auto model = glimpse::train(Dataset(), params);
  ASSERT_TRUE(model.ok()) << model.error().message;
  model->feature_version = kFeaturePipelineVersion - 1;  // stored before a numerics change
  NewModel old{"old", "", model->methods, model->default_method, "{}", model->stats, glimpse::serialize(*model)};
  old.feature_version = model->feature_version;
  ASSERT_TRUE(h.store->Put(old).ok());
  const Cloud cloud = Sample("box", 5, 1).cloud;
  const std::string version_text = "feature pipeline version " + std::to_string(kFeaturePipelineVersion - 1);

  grpc::ClientContext c1;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("old");
  *req.mutable_cloud() = wire::CloudToProto(cloud);
  v1::ClassifyResponse resp;
  grpc::Status s = h.stub->Classify(&c1, req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr(version_text));
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("retrain"));

  grpc::ClientContext c2;
  v1::ClassifyBatchRequest batch;
  batch.mutable_model()->set_name("old");
  *batch.add_clouds() = wire::CloudToProto(cloud);
  *batch.add_clouds() = wire::CloudToProto(cloud);
  v1::ClassifyBatchResponse batch_resp;
  s = h.stub->ClassifyBatch(&c2, batch, &batch_resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr(version_text));

  grpc::ClientContext c3;
  auto stream = h.stub->StreamClassify(&c3);
  v1::ScanChunk chunk;
  chunk.mutable_model()->set_name("old");
  *chunk.mutable_cloud() = wire::CloudToProto(cloud);
  stream->Write(chunk);
  v1::Decision d;
  EXPECT_FALSE(stream->Read(&d));
  s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr(version_text));

  grpc::ClientContext c4;
  v1::GetModelRequest get;
  get.mutable_model()->set_name("old");
  v1::ModelInfo info;
  ASSERT_TRUE(h.stub->GetModel(&c4, get, &info).ok());
  EXPECT_EQ(info.feature_version(), kFeaturePipelineVersion - 1);  // ModelInfo says which version it is
}

TEST_F(CoreEngineTest, CoreRejectionsComeBackAsInvalidArgument) {
  grpc::ClientContext ctx;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("shapes");
  Cloud few;
  few.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};  // below core's min_points
  *req.mutable_cloud() = wire::CloudToProto(few);
  v1::ClassifyResponse resp;
  EXPECT_EQ(harness_->stub->Classify(&ctx, req, &resp).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST(CoreEngine, SingleCategoryTrainingIsRejected) {
  testing::Harness h(Limits{}, [](ServiceOptions& o) { o.engine = CoreEngine(); });
  grpc::ClientContext ctx;
  auto stream = h.stub->Train(&ctx);
  v1::TrainRequest header;
  *header.mutable_header() = FastTrainHeader("shapes");
  stream->Write(header);
  for (int i = 0; i < 2; ++i) {
    TrainingCloud lc = Sample("box", i, 0);
    v1::TrainRequest req;
    req.mutable_cloud()->set_category(lc.category);
    *req.mutable_cloud()->mutable_cloud() = wire::CloudToProto(lc.cloud);
    stream->Write(req);
  }
  stream->WritesDone();
  for (v1::TrainProgress p; stream->Read(&p);) {
  }
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);  // as the proto documents
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("2 categories"));
  EXPECT_TRUE(h.store->List()->empty());
}

TEST(CoreEngine, ParametersReachCoresTrainParams) {
  v1::TrainHeader h = FastTrainHeader("shapes");
  h.add_methods(v1::METHOD_BOK);
  h.add_methods(v1::METHOD_VFH);
  h.mutable_parameters()->set_support_radius_m(0.04);
  h.mutable_parameters()->set_decision(v1::DECISION_KIND_CENTRES);
  h.mutable_parameters()->set_centres_per_category(2);
  h.mutable_parameters()->set_neighbours(3);
  h.mutable_parameters()->set_kgh_distance_bins(9);
  h.mutable_parameters()->set_normalise_histograms(false);
  auto spec = wire::TrainSpecFromProto(h);
  ASSERT_TRUE(spec.ok());
  auto p = wire::ToTrainParams(*spec);
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p->methods, (std::vector<MethodId>{MethodId::kBoK, MethodId::kVFH}));
  EXPECT_EQ(p->default_method, MethodId::kBoK);  // fusion was not asked for
  EXPECT_FLOAT_EQ(p->features.surface.support_radius_m, 0.04f);
  EXPECT_EQ(p->bok_clusters, 6);
  EXPECT_EQ(p->bog_keypoint_clusters, 3);
  EXPECT_EQ(p->bog_volume_clusters, 2);
  EXPECT_EQ(p->bog_pca_dims, 8);
  EXPECT_EQ(p->kgh_clusters, 3);
  EXPECT_EQ(p->kgh_distance_bins, 9);
  EXPECT_EQ(p->decision.kind, DecisionRule::kCentres);
  EXPECT_EQ(p->decision.centres_per_category, 2);
  EXPECT_EQ(p->decision.neighbours, 3);
  EXPECT_FALSE(p->normalise_histograms);
  EXPECT_EQ(p->seed, 11u);

  auto defaults = wire::ToTrainParams(wire::TrainSpec{});
  ASSERT_TRUE(defaults.ok());
  const TrainParams core_defaults;
  EXPECT_EQ(defaults->methods, core_defaults.methods);
  EXPECT_EQ(defaults->default_method, core_defaults.default_method);
  EXPECT_EQ(defaults->bok_clusters, core_defaults.bok_clusters);
  EXPECT_EQ(defaults->decision.kind, core_defaults.decision.kind);
  EXPECT_EQ(defaults->seed, core_defaults.seed);
}

}  // namespace
}  // namespace glimpse::server
