// ClassifyScene over gRPC with the real recogniser: every object of a depth camera's frame is found with
// its box and answered as Classify answers its points alone; bad requests are clear statuses and the
// server keeps serving.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "common/fast_training.h"
#include "core/synthetic_scene.h"
#include "fakes.h"
#include "proto/wire/clouds.h"
#include "shapes.h"

namespace glimpse::server {
namespace {

using glimpse::testing::FastTrainHeader;
using testing::Dataset;
using testing::Harness;
using testing::TrainOverGrpc;

Cloud Finite(Cloud frame) {
  std::erase_if(frame.points, [](const Vec3& p) { return !p.allFinite(); });
  return frame;
}

Vec3 Of(const v1::Vec3& v) { return Vec3(v.x(), v.y(), v.z()); }

class ClassifySceneTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Limits limits;
    limits.max_points_per_cloud = 400'000;
    harness_ = new Harness(limits, [](ServiceOptions& o) { o.engine = CoreEngine(); });
    auto trained = TrainOverGrpc(*harness_->stub, FastTrainHeader("shapes"), Dataset());
    ASSERT_TRUE(trained.status.ok()) << trained.status.error_message();
  }
  static void TearDownTestSuite() { delete harness_; }

  static grpc::Status Call(const v1::ClassifySceneRequest& request, v1::ClassifySceneResponse* response) {
    grpc::ClientContext ctx;
    return harness_->stub->ClassifyScene(&ctx, request, response);
  }
  static v1::ClassifySceneRequest Request(const Cloud& frame) {
    v1::ClassifySceneRequest r;
    r.mutable_model()->set_name("shapes");
    *r.mutable_frame() = wire::CloudToProto(frame);
    return r;
  }

  static inline Harness* harness_ = nullptr;
};

TEST_F(ClassifySceneTest, FindsEveryObjectAndAnswersEachAsClassifyWould) {
  const test::SyntheticScene scene = test::four_object_scene();
  const Cloud frame = Finite(scene.frame);
  v1::ClassifySceneRequest request = Request(frame);
  request.set_return_indices(true);
  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(request, &response).ok());
  EXPECT_EQ(response.model().version(), 1u);
  EXPECT_EQ(response.frame_points(), frame.points.size());
  EXPECT_EQ(response.warning(), "");
  ASSERT_GE(response.planes_size(), 1);
  EXPECT_GT(std::abs(response.planes(0).normal().z()), 0.9f);  // the floor, largest
  ASSERT_EQ(response.objects_size(), 4);
  float last_range = 0;
  for (const v1::SceneObject& o : response.objects()) {
    EXPECT_GE(o.range_m(), last_range);  // nearest first
    last_range = o.range_m();
    // Its box is one shape's true box, to a few centimetres.
    const Vec3 centre = 0.5f * (Of(o.box_min()) + Of(o.box_max()));
    float best = INFINITY;
    for (const Bounds& truth : scene.truth) best = std::min(best, (truth.centre() - centre).norm());
    EXPECT_LT(best, 0.03f);
    ASSERT_EQ(o.indices_size(), static_cast<int>(o.points()));
    EXPECT_TRUE(std::is_sorted(o.indices().begin(), o.indices().end()));

    // The answer is Classify's of the object's points with the frame's sensor.
    ASSERT_EQ(o.result().code(), 0) << o.result().message();
    Cloud alone{{}, frame.sensor, frame.frame};
    for (uint32_t i : o.indices()) alone.points.push_back(frame.points[i]);
    grpc::ClientContext ctx;
    v1::ClassifyRequest single;
    single.mutable_model()->set_name("shapes");
    *single.mutable_cloud() = wire::CloudToProto(alone);
    v1::ClassifyResponse expected;
    ASSERT_TRUE(harness_->stub->Classify(&ctx, single, &expected).ok());
    const v1::ClassifyResponse& got = o.result().response();
    EXPECT_EQ(got.winner(), expected.winner());
    ASSERT_EQ(got.scores_size(), expected.scores_size());
    for (int k = 0; k < got.scores_size(); ++k) EXPECT_EQ(got.scores(k).score(), expected.scores(k).score());
    EXPECT_EQ(got.unknown(), expected.unknown());
    EXPECT_EQ(got.points(), expected.points());
  }
}

TEST_F(ClassifySceneTest, IndicesComeOnlyWhenAsked) {
  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(Request(Finite(test::four_object_scene().frame)), &response).ok());
  ASSERT_EQ(response.objects_size(), 4);
  for (const v1::SceneObject& o : response.objects()) {
    EXPECT_EQ(o.indices_size(), 0);
    EXPECT_GT(o.points(), 200u);
  }
}

// A 320 x 240 frame holds a quarter of the points: its objects are asked for fewer by default, and as
// many as a 640 x 480 frame's with reference_density_per_deg2 0 (some are then lost).
TEST_F(ClassifySceneTest, AFrameOfHalfTheResolutionFindsTheSameObjects) {
  const test::SyntheticScene half = test::four_object_scene(1, 320, 240);
  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(Request(Finite(half.frame)), &response).ok());
  EXPECT_EQ(response.objects_size(), 4);
  v1::ClassifySceneRequest as_given = Request(Finite(half.frame));
  as_given.mutable_scene()->set_reference_density_per_deg2(0);
  ASSERT_TRUE(Call(as_given, &response).ok());
  EXPECT_LT(response.objects_size(), 4);
}

TEST_F(ClassifySceneTest, AFrameWhoseUpIsNotZIsWarned) {
  Cloud frame = Finite(test::four_object_scene().frame);
  for (Vec3& p : frame.points) p = Vec3(p.x(), -p.z(), p.y());  // a camera's own coordinates: y down
  *frame.sensor = Vec3(frame.sensor->x(), -frame.sensor->z(), frame.sensor->y());
  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(Request(frame), &response).ok());
  EXPECT_THAT(response.warning(), ::testing::HasSubstr("is +z up?"));
}

TEST_F(ClassifySceneTest, AFloorAloneHoldsNoObject) {
  test::SyntheticScene empty = test::render_scene(test::Room{}, {}, Vec3(0, 0, 1.3f), Vec3(0, 2.25f, 0));
  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(Request(Finite(empty.frame)), &response).ok());
  EXPECT_EQ(response.objects_size(), 0);
  EXPECT_GE(response.planes_size(), 1);
}

TEST_F(ClassifySceneTest, BadRequestsAreClearStatusesAndTheServerKeepsServing) {
  const Cloud frame = Finite(test::four_object_scene().frame);
  auto status_of = [](const v1::ClassifySceneRequest& r) {
    v1::ClassifySceneResponse response;
    return Call(r, &response);
  };
  v1::ClassifySceneRequest bad = Request(frame);
  bad.mutable_scene()->set_cluster_tolerance_m(-1);
  grpc::Status s = status_of(bad);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("scene.cluster_tolerance_m"));

  bad = Request(frame);
  bad.mutable_scene()->set_reference_density_per_deg2(-5);
  s = status_of(bad);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("scene.reference_density_per_deg2"));

  bad = Request(frame);
  bad.mutable_model()->set_name("nothing");
  EXPECT_EQ(status_of(bad).error_code(), grpc::StatusCode::NOT_FOUND);

  bad = Request(frame);
  bad.set_method(v1::METHOD_BOK);  // not trained
  EXPECT_EQ(status_of(bad).error_code(), grpc::StatusCode::FAILED_PRECONDITION);

  bad = Request(frame);
  std::string xyz = bad.frame().xyz();
  const float nan = std::nanf("");
  std::memcpy(xyz.data(), &nan, sizeof nan);
  bad.mutable_frame()->set_xyz(xyz);
  s = status_of(bad);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("the frame"));

  Cloud large = frame;
  while (large.points.size() <= 400'000) large.points.insert(large.points.end(), frame.points.begin(), frame.points.end());
  EXPECT_EQ(status_of(Request(large)).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);

  v1::ClassifySceneResponse response;
  ASSERT_TRUE(Call(Request(frame), &response).ok());
  EXPECT_EQ(response.objects_size(), 4);
}

}  // namespace
}  // namespace glimpse::server
