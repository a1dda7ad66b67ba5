// A StreamClassify that follows one object among others (ScanChunk.track) with the real recogniser: a
// camera moves round four objects, every chunk a whole frame; each reply says where the target is, and
// the scan fused is the target's alone, as a plain stream of its clusters would decide it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "common/fast_training.h"
#include "core/synthetic_scene.h"
#include "fakes.h"
#include "glimpse/session/scene_tracking.h"
#include "proto/wire/clouds.h"
#include "shapes.h"

namespace glimpse::server {
namespace {

using glimpse::testing::FastTrainHeader;
using test::SceneShape;
using testing::Dataset;
using testing::Harness;
using testing::TrainOverGrpc;

const std::vector<SceneShape> kShapes = {{SceneShape::kBox, Vec3(-0.7f, 1.9f, 0), Vec3(0.3f, 0.2f, 0.4f)},
                                         {SceneShape::kCylinder, Vec3(-0.15f, 2.3f, 0), Vec3(0.1f, 0, 0.35f)},
                                         {SceneShape::kBox, Vec3(0.15f, 2.3f, 0), Vec3(0.3f, 0.3f, 0.3f)},
                                         {SceneShape::kSphere, Vec3(0.6f, 1.8f, 0), Vec3(0.15f, 0, 0)}};
const Vec3 kCentre(0, 2.2f, 0.15f);
const Vec3 kCylinder(-0.15f, 2.3f, 0.175f);  // the target: 5 cm from the box beside it

// A 320 x 240 frame from `azimuth_deg` round the group (0: from the front), finite points only, with
// its sensor and camera frame.
Cloud FrameFrom(float azimuth_deg, const Vec3& look_at = kCentre) {
  const float a = azimuth_deg * std::numbers::pi_v<float> / 180.f;
  const Vec3 sensor = kCentre + Vec3(2.2f * std::sin(a), -2.2f * std::cos(a), 1.15f);
  test::SyntheticScene s = test::render_scene(test::Room{}, kShapes, sensor, look_at, 320, 240);
  const Vec3 forward = (look_at - sensor).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  s.frame.frame = CameraFrame{forward, right.cross(forward), 57.f, 43.f};
  std::erase_if(s.frame.points, [](const Vec3& p) { return !p.allFinite(); });
  return s.frame;
}

v1::ScanChunk Chunk(const Cloud& frame) {
  v1::ScanChunk c;
  *c.mutable_cloud() = wire::CloudToProto(frame);
  return c;
}

struct StreamResult {
  std::vector<v1::Decision> decisions;
  grpc::Status status;
};

StreamResult Stream(v1::Glimpse::Stub& stub, std::vector<v1::ScanChunk> chunks) {
  grpc::ClientContext ctx;
  auto stream = stub.StreamClassify(&ctx);
  StreamResult out;
  for (const v1::ScanChunk& c : chunks) {
    if (!stream->Write(c)) break;
    v1::Decision d;
    if (!stream->Read(&d)) break;
    out.decisions.push_back(d);
  }
  stream->WritesDone();
  for (v1::Decision d; stream->Read(&d);) out.decisions.push_back(d);
  out.status = stream->Finish();
  return out;
}

// The first chunk of a tracking stream of `frame`: the model and the cylinder's point (a 320 x 240 frame's
// objects need fewer points: segment_scene scales its threshold to the frame's density).
v1::ScanChunk TrackingFirst(const Cloud& frame) {
  v1::ScanChunk c = Chunk(frame);
  c.mutable_model()->set_name("shapes");
  c.mutable_track()->mutable_point()->set_x(kCylinder.x());
  c.mutable_track()->mutable_point()->set_y(kCylinder.y());
  c.mutable_track()->mutable_point()->set_z(kCylinder.z());
  return c;
}

class TrackStreamTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    harness_ = new Harness({}, [](ServiceOptions& o) { o.engine = CoreEngine(); });
    auto trained = TrainOverGrpc(*harness_->stub, FastTrainHeader("shapes"), Dataset());
    ASSERT_TRUE(trained.status.ok()) << trained.status.error_message();
  }
  static void TearDownTestSuite() { delete harness_; }
  static v1::ScanChunk First(const Cloud& frame) { return TrackingFirst(frame); }
  static inline Harness* harness_ = nullptr;
};

TEST_F(TrackStreamTest, FollowsTheTargetAmongOthersAndDecidesItsPointsAlone) {
  const std::vector<float> azimuths = {-35, -20, -5, 10, 25, 40};
  std::vector<v1::ScanChunk> chunks;
  for (size_t i = 0; i < azimuths.size(); ++i)
    chunks.push_back(i == 0 ? First(FrameFrom(azimuths[i])) : Chunk(FrameFrom(azimuths[i])));
  const StreamResult tracked = Stream(*harness_->stub, chunks);
  ASSERT_TRUE(tracked.status.ok()) << tracked.status.error_message();
  ASSERT_EQ(tracked.decisions.size(), azimuths.size() + 1);  // one per frame, then the final one

  // Each frame shows the target: the cylinder's cluster, never the box 5 cm beside it. The plain stream
  // sends what core's tracker finds new of it in each frame.
  TrackTarget target;
  target.kind = TrackTarget::Kind::kPoint;
  target.point = kCylinder;
  TrackParams params;
  Expected<SceneTracker> local = SceneTracker::create(target, params);
  ASSERT_TRUE(local.ok());
  std::vector<v1::ScanChunk> plain;
  for (size_t i = 0; i < azimuths.size(); ++i) {
    const v1::Decision& d = tracked.decisions[i];
    ASSERT_TRUE(d.tracked().found()) << "frame " << i << ": " << d.tracked().not_found();
    EXPECT_EQ(d.tracked().objects(), 4u);
    const v1::SceneObject& o = d.tracked().object();
    EXPECT_LT(std::hypot(o.centroid().x() - kCylinder.x(), o.centroid().y() - kCylinder.y()), 0.1f) << "frame " << i;
    EXPECT_LT(o.box_max().x() - o.box_min().x(), 0.25f) << "frame " << i;  // the cylinder alone is 0.2 m wide
    if (i > 0) {
      EXPECT_GE(d.points(), tracked.decisions[i - 1].points());
    }
    const Cloud frame = wire::CloudFromProto(chunks[i].cloud(), 1'000'000).value();
    Expected<TrackStep> step = local->next(frame);
    ASSERT_TRUE(step.ok() && step->found);
    EXPECT_EQ(step->object.points.size(), o.points());
    plain.push_back(Chunk(Cloud{step->fresh, frame.sensor, frame.frame}));
  }
  ASSERT_EQ(plain.size(), azimuths.size());
  plain.front().mutable_model()->set_name("shapes");
  const StreamResult alone = Stream(*harness_->stub, plain);
  ASSERT_TRUE(alone.status.ok()) << alone.status.error_message();
  ASSERT_EQ(alone.decisions.size(), tracked.decisions.size());
  const v1::Decision& final_tracked = tracked.decisions.back();
  const v1::Decision& final_alone = alone.decisions.back();
  EXPECT_TRUE(final_tracked.final());
  EXPECT_EQ(final_tracked.points(), final_alone.points());
  EXPECT_EQ(final_tracked.winner(), final_alone.winner());
  ASSERT_EQ(final_tracked.scores_size(), final_alone.scores_size());
  for (int k = 0; k < final_tracked.scores_size(); ++k)
    EXPECT_EQ(final_tracked.scores(k).score(), final_alone.scores(k).score());
}

// Thirty frames of a still camera fit a session of three times the target's points: each frame adds only
// the surface earlier ones did not reach (1 cm cells), never a new noisy copy.
TEST(TrackStream, AStillCameraStreamsOnWithinTheSessionLimit) {
  const Cloud frame = FrameFrom(10);
  Expected<Scene> scene = segment_scene(frame);
  ASSERT_TRUE(scene.ok());
  size_t target_points = 0;
  for (const SceneObject& o : scene->objects)
    if (std::hypot(o.centroid.x() - kCylinder.x(), o.centroid.y() - kCylinder.y()) < 0.1f) target_points = o.points.size();
  ASSERT_GT(target_points, 250u);
  Limits limits;
  limits.max_session_points = 3 * target_points;
  Harness h(limits, [](ServiceOptions& o) { o.engine = CoreEngine(); });
  ASSERT_TRUE(TrainOverGrpc(*h.stub, FastTrainHeader("shapes"), Dataset()).status.ok());
  std::vector<v1::ScanChunk> chunks;
  for (uint32_t k = 0; k < 30; ++k) {
    const float a = 10.f * std::numbers::pi_v<float> / 180.f;
    const Vec3 sensor = kCentre + Vec3(2.2f * std::sin(a), -2.2f * std::cos(a), 1.15f);
    test::SyntheticScene s = test::render_scene(test::Room{}, kShapes, sensor, kCentre, 320, 240, 0.004f, 50 + k);
    std::erase_if(s.frame.points, [](const Vec3& p) { return !p.allFinite(); });
    chunks.push_back(k == 0 ? TrackingFirst(s.frame) : Chunk(s.frame));
  }
  const StreamResult r = Stream(*h.stub, chunks);
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.decisions.size(), chunks.size() + 1);
  for (size_t k = 0; k < chunks.size(); ++k) EXPECT_TRUE(r.decisions[k].tracked().found()) << k;
  EXPECT_GT(r.decisions[chunks.size() - 1].points(), r.decisions[0].points());
  // The last ten frames add under a tenth of one frame's cluster: the fused surface saturates.
  EXPECT_LT(10 * (r.decisions[chunks.size() - 1].points() - r.decisions[chunks.size() - 11].points()), target_points);
}

TEST_F(TrackStreamTest, AFrameWithoutTheTargetRepeatsTheDecisionAndSaysWhy) {
  // The second frame looks far to the right of the group: the target is out of view.
  const Cloud away = FrameFrom(0, kCentre + Vec3(3.5f, 0.5f, 0));
  const StreamResult r = Stream(*harness_->stub, {First(FrameFrom(0)), Chunk(away), Chunk(FrameFrom(15))});
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.decisions.size(), 4u);
  EXPECT_TRUE(r.decisions[0].tracked().found());
  EXPECT_FALSE(r.decisions[1].tracked().found());
  EXPECT_THAT(r.decisions[1].tracked().not_found(), ::testing::Not(::testing::IsEmpty()));
  EXPECT_EQ(r.decisions[1].points(), r.decisions[0].points());  // nothing fused
  EXPECT_EQ(r.decisions[1].chunk_index(), 1u);
  EXPECT_TRUE(r.decisions[2].tracked().found());  // seen again
  EXPECT_GT(r.decisions[2].points(), r.decisions[1].points());
}

TEST_F(TrackStreamTest, BadTrackingStreamsAreInvalidArguments) {
  auto code_of = [](std::vector<v1::ScanChunk> chunks) { return Stream(*harness_->stub, chunks).status; };
  v1::ScanChunk no_target = First(FrameFrom(0));
  no_target.mutable_track()->Clear();
  grpc::Status s = code_of({no_target});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("names no target"));

  v1::ScanChunk again = First(FrameFrom(10));
  again.clear_model();
  s = code_of({First(FrameFrom(0)), again});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("only the first chunk names a target"));

  Cloud blind = FrameFrom(0);
  blind.sensor.reset();
  blind.frame.reset();
  v1::ScanChunk no_sensor = First(blind);
  s = code_of({no_sensor});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), ::testing::HasSubstr("need their sensor"));

  v1::ScanChunk scene_alone = Chunk(FrameFrom(0));
  scene_alone.mutable_model()->set_name("shapes");
  scene_alone.mutable_scene()->set_cluster_tolerance_m(0.05f);
  EXPECT_EQ(code_of({scene_alone}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  v1::ScanChunk bad_box = First(FrameFrom(0));
  bad_box.mutable_track()->mutable_box()->mutable_min()->set_x(1);  // min above max
  EXPECT_EQ(code_of({bad_box}).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

}  // namespace
}  // namespace glimpse::server
