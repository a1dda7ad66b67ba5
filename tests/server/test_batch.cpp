// ClassifyBatch over an in-process channel with the fake engine: every cloud answered in order with
// its own status, the answers Classify gives one by one, the limits applying to the batch as a whole,
// and what fails the whole call (the codes the proto documents).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fakes.h"

namespace glimpse::server {
namespace {

using ::testing::HasSubstr;
using testing::Harness;
using testing::SpiralCloud;

v1::ClassifyBatchRequest BatchReq(const std::string& model, const std::vector<size_t>& points) {
  v1::ClassifyBatchRequest req;
  req.mutable_model()->set_name(model);
  for (size_t n : points) *req.add_clouds() = wire::CloudToProto(SpiralCloud(n));
  return req;
}

grpc::Status Batch(Harness& h, const v1::ClassifyBatchRequest& req, v1::ClassifyBatchResponse* resp) {
  grpc::ClientContext ctx;
  return h.stub->ClassifyBatch(&ctx, req, resp);
}

class BatchTest : public ::testing::Test {
 protected:
  explicit BatchTest(Limits limits = {}) : h_(limits) {}
  void SetUp() override {
    v1::TrainProgress t;
    ASSERT_TRUE(h_.Train("m", {"a", "b", "c"}, &t).ok());
  }
  Harness h_;
};

TEST_F(BatchTest, EveryCloudIsAnsweredInOrderAsClassifyAnswersIt) {
  const std::vector<size_t> sizes = {10, 11, 12, 5000};
  v1::ClassifyBatchResponse resp;
  ASSERT_TRUE(Batch(h_, BatchReq("m", sizes), &resp).ok());
  ASSERT_EQ(resp.results_size(), 4);
  EXPECT_EQ(resp.model().name(), "m");
  EXPECT_EQ(resp.model().version(), 1u);
  EXPECT_EQ(resp.method(), v1::METHOD_FUSION);
  for (size_t i = 0; i < sizes.size(); ++i) {
    const v1::ClassifyResult& r = resp.results(int(i));
    EXPECT_EQ(r.code(), 0);
    EXPECT_EQ(r.message(), "");
    v1::ClassifyRequest single;
    single.mutable_model()->set_name("m");
    *single.mutable_cloud() = wire::CloudToProto(SpiralCloud(sizes[i]));
    v1::ClassifyResponse alone;
    grpc::ClientContext ctx;
    ASSERT_TRUE(h_.stub->Classify(&ctx, single, &alone).ok());
    EXPECT_EQ(r.response().winner(), alone.winner()) << i;
    EXPECT_EQ(r.response().winner_index(), int(sizes[i] % 3));
    EXPECT_EQ(r.response().points(), alone.points());
    EXPECT_EQ(r.response().model().version(), 1u);
    EXPECT_EQ(r.response().warning(), alone.warning());
    ASSERT_EQ(r.response().scores_size(), 3);
  }
  EXPECT_EQ(resp.results(3).response().warning(), "the cloud is large");
}

TEST_F(BatchTest, EachBadCloudFailsAloneWithItsOwnCode) {
  v1::ClassifyBatchRequest req = BatchReq("m", {10, 2, 10, 10});
  req.mutable_clouds(2)->mutable_xyz()->push_back('x');  // not a multiple of 12 bytes
  Cloud nan = SpiralCloud(10);
  nan.points[4].y() = std::nanf("");
  *req.mutable_clouds(3) = wire::CloudToProto(nan);
  v1::ClassifyBatchResponse resp;
  ASSERT_TRUE(Batch(h_, req, &resp).ok());
  ASSERT_EQ(resp.results_size(), 4);
  EXPECT_EQ(resp.results(0).code(), 0);
  EXPECT_EQ(resp.results(1).code(), int(grpc::StatusCode::INVALID_ARGUMENT));  // the engine's "too few points"
  EXPECT_THAT(resp.results(1).message(), HasSubstr("cloud 1: too few points"));
  EXPECT_FALSE(resp.results(1).has_response());
  EXPECT_EQ(resp.results(2).code(), int(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(resp.results(2).message(), HasSubstr("cloud 2: xyz has 121 bytes"));
  EXPECT_EQ(resp.results(3).code(), int(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(resp.results(3).message(), HasSubstr("cloud 3: xyz: point 4 is not finite"));
}

TEST_F(BatchTest, WhatConcernsEveryCloudFailsTheCall) {
  v1::ClassifyBatchResponse resp;
  EXPECT_EQ(Batch(h_, BatchReq("nobody", {10}), &resp).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Batch(h_, BatchReq("", {10}), &resp).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(Batch(h_, BatchReq("m", {}), &resp).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  auto unknown = BatchReq("m", {10});
  unknown.set_method(static_cast<v1::Method>(42));
  EXPECT_EQ(Batch(h_, unknown, &resp).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  auto lacking = BatchReq("m", {10, 11});
  lacking.set_method(v1::METHOD_ESF);  // the fake trains bok and fusion
  grpc::Status s = Batch(h_, lacking, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("esf"));
  h_.behaviour.classify_error = failed_precondition("the model was trained with feature pipeline version 1");
  s = Batch(h_, BatchReq("m", {10, 11}), &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("feature pipeline version"));
  EXPECT_EQ(resp.results_size(), 0);
}

TEST_F(BatchTest, ADeadlineThatPassedIsDeadlineExceeded) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() - std::chrono::seconds(1));
  v1::ClassifyBatchResponse resp;
  EXPECT_EQ(h_.stub->ClassifyBatch(&ctx, BatchReq("m", {10}), &resp).error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
}

class SmallLimits : public BatchTest {
 protected:
  static Limits Small() {
    Limits l;
    l.max_points_per_cloud = 100;
    l.max_batch_clouds = 3;
    return l;
  }
  SmallLimits() : BatchTest(Small()) {}
};

TEST_F(SmallLimits, TheLimitsApplyToTheBatchAsAWhole) {
  v1::ClassifyBatchResponse resp;
  ASSERT_TRUE(Batch(h_, BatchReq("m", {50, 50}), &resp).ok());  // 100 points in all: at the limit
  grpc::Status s = Batch(h_, BatchReq("m", {50, 51}), &resp);   // each under it, together over
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("101 points in all"));
  s = Batch(h_, BatchReq("m", {10, 10, 10, 10}), &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("4 clouds"));
  EXPECT_EQ(h_.metrics.RequestCount("ClassifyBatch", grpc::StatusCode::RESOURCE_EXHAUSTED), 2);
}

}  // namespace
}  // namespace glimpse::server
