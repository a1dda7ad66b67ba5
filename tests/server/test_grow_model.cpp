// Growing a stored model over gRPC (TrainHeader.base) with the real recogniser: the grown version decides
// as the model a training of every cloud at once gives, and a base that cannot grow is a clear status with
// nothing stored.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>

#include "common/fast_training.h"
#include "fakes.h"
#include "glimpse/learning/model.h"
#include "proto/wire/clouds.h"
#include "shapes.h"

namespace glimpse::server {
namespace {

using glimpse::testing::FastTrainHeader;
using testing::Dataset;
using testing::Harness;
using testing::Sample;
using testing::TrainOverGrpc;

std::vector<TrainingCloud> Of(const std::vector<TrainingCloud>& data, const std::string& category, bool keep) {
  std::vector<TrainingCloud> out;
  for (const TrainingCloud& c : data)
    if ((c.category == category) == keep) out.push_back(c);
  return out;
}

v1::TrainHeader GrowHeader(const std::string& name, const std::string& base, uint32_t version = 0) {
  v1::TrainHeader h;
  h.set_model_name(name);
  h.mutable_base()->set_name(base);
  h.mutable_base()->set_version(version);
  return h;
}

std::optional<Model> Stored(const Harness& h, uint64_t id) {
  auto blob = h.store->Blob(static_cast<int64_t>(id));
  EXPECT_TRUE(blob.ok());
  if (!blob.ok()) return std::nullopt;
  auto model = glimpse::deserialize(*blob);
  EXPECT_TRUE(model.ok()) << model.error().message;
  if (!model.ok()) return std::nullopt;
  return std::move(*model);
}

Harness CoreHarness(Limits limits = {}) {
  return Harness(limits, [](ServiceOptions& o) { o.engine = CoreEngine(); });
}

TEST(GrowModel, AGrownVersionDecidesAsATrainingOfEveryCloudAtOnce) {
  Harness h = CoreHarness();
  const std::vector<TrainingCloud> all = Dataset();
  auto base = TrainOverGrpc(*h.stub, FastTrainHeader("shapes"), Of(all, "sphere", false));
  ASSERT_TRUE(base.status.ok()) << base.status.error_message();
  EXPECT_GT(base.last.model().training_set_bytes(), 0u);
  EXPECT_EQ(base.last.model().grown_from(), "");

  auto grown = TrainOverGrpc(*h.stub, GrowHeader("shapes", "shapes"), Of(all, "sphere", true));
  ASSERT_TRUE(grown.status.ok()) << grown.status.error_message();
  const v1::ModelInfo& m = grown.last.model();
  EXPECT_EQ(m.version(), 2u);
  EXPECT_EQ(m.grown_from(), "shapes:1");
  EXPECT_THAT(m.categories(), ::testing::ElementsAre("box", "cylinder", "sphere"));
  EXPECT_EQ(m.stats().clouds(), all.size());
  EXPECT_EQ(m.parameters().seed(), 11u);  // the base's parameters
  EXPECT_GT(m.training_set_bytes(), base.last.model().training_set_bytes());

  // It decides as a training of every cloud at once (its logistic decisions started from the base's).
  auto full = TrainOverGrpc(*h.stub, FastTrainHeader("all"), all);
  ASSERT_TRUE(full.status.ok()) << full.status.error_message();
  const std::optional<Model> grown_model = Stored(h, m.id()), full_model = Stored(h, full.last.model().id());
  ASSERT_TRUE(grown_model && full_model);
  EXPECT_EQ(grown_model->categories, full_model->categories);
  EXPECT_EQ(grown_model->stats.clouds_per_category, full_model->stats.clouds_per_category);
  for (const TrainingCloud& c : all) {
    auto a = glimpse::classify(*grown_model, c.cloud);
    auto b = glimpse::classify(*full_model, c.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->winner, b->winner);
    for (size_t k = 0; k < b->scores.size(); ++k) EXPECT_NEAR(a->scores[k], b->scores[k], 0.01);
  }

  // Served like any version: a sphere is a sphere.
  grpc::ClientContext ctx;
  v1::ClassifyRequest req;
  req.mutable_model()->set_name("shapes");
  *req.mutable_cloud() = wire::CloudToProto(Sample("sphere", 7, 3).cloud);
  v1::ClassifyResponse resp;
  ASSERT_TRUE(h.stub->Classify(&ctx, req, &resp).ok());
  EXPECT_EQ(resp.model().version(), 2u);
  EXPECT_EQ(resp.winner(), "sphere");
}

TEST(GrowModel, ABaseThatCannotGrowIsAClearStatusAndNothingIsStored) {
  Limits keep_none;
  keep_none.max_training_set_bytes = 0;
  Harness h = CoreHarness(keep_none);
  const std::vector<TrainingCloud> all = Dataset();
  auto base = TrainOverGrpc(*h.stub, FastTrainHeader("shapes"), Of(all, "sphere", false));
  ASSERT_TRUE(base.status.ok()) << base.status.error_message();
  EXPECT_EQ(base.last.model().training_set_bytes(), 0u);
  const std::vector<TrainingCloud> spheres = Of(all, "sphere", true);

  auto none_kept = TrainOverGrpc(*h.stub, GrowHeader("shapes", "shapes"), spheres);
  EXPECT_EQ(none_kept.status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(none_kept.status.error_message(), ::testing::HasSubstr("keeps no training set"));

  auto missing = TrainOverGrpc(*h.stub, GrowHeader("shapes", "shapes", 9), spheres);
  EXPECT_EQ(missing.status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(missing.status.error_message(), ::testing::HasSubstr("base"));

  v1::TrainHeader with_methods = GrowHeader("shapes", "shapes");
  with_methods.add_methods(v1::METHOD_VFH);
  auto mixed = TrainOverGrpc(*h.stub, with_methods, spheres);
  EXPECT_EQ(mixed.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(mixed.status.error_message(), ::testing::HasSubstr("base's methods and parameters"));

  EXPECT_EQ(h.store->List()->size(), 1u);  // the base alone
}

}  // namespace
}  // namespace glimpse::server
