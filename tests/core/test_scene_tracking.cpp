// Following one object through a stream of scene frames (session/scene_tracking.h), on frames made by hand
// (synthetic_scene.h): the camera moves, the objects stand still, every frame in world coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "glimpse/session/scene_tracking.h"
#include "synthetic_scene.h"

namespace glimpse {
namespace {

using test::SceneShape;
using test::SyntheticScene;

// A 320 x 240 frame from `sensor` looking at `target`, with the camera frame render_scene draws it through.
SyntheticScene camera_frame(const std::vector<SceneShape>& shapes, const Vec3& sensor, const Vec3& target,
                            const test::Room& room = {3.f, 4.f, 2.f}) {
  SyntheticScene s = test::render_scene(room, shapes, sensor, target, 320, 240);
  const Vec3 forward = (target - sensor).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  s.frame.frame = CameraFrame{forward, right.cross(forward), 57.f, 43.f};
  return s;
}

// The frames are 320 x 240, with the default parameters: segment_scene asks their objects for fewer points.
SceneTracker make_tracker(const TrackTarget& target, const TrackParams& params = {}) {
  Expected<SceneTracker> tracker = SceneTracker::create(target, params);
  if (!tracker.ok()) {
    ADD_FAILURE() << tracker.error().message;
    std::abort();
  }
  return std::move(tracker).value();
}

TrackStep step_of(SceneTracker& tracker, const Cloud& frame) {
  Expected<TrackStep> step = tracker.next(frame);
  EXPECT_TRUE(step.ok()) << step.error().message;
  return step.ok() ? std::move(step).value() : TrackStep{};
}

// The found object is the shape whose visible points span `truth`: its box within 3 cm of theirs, but
// for its foot, which the floor's inliers take as high as the floor's reach at its range.
void expect_is(const TrackStep& step, const Bounds& truth) {
  ASSERT_TRUE(step.found) << step.not_found;
  EXPECT_LT((step.object.box_min - truth.min).head<2>().cwiseAbs().maxCoeff(), 0.03f) << step.object.box_min.transpose();
  const float reach = 0.02f + 0.003f * step.object.range_m * step.object.range_m;
  EXPECT_LT(std::abs(step.object.box_min.z() - truth.min.z()), reach + 0.01f) << step.object.box_min.transpose();
  EXPECT_LT((step.object.box_max - truth.max).cwiseAbs().maxCoeff(), 0.03f) << step.object.box_max.transpose();
}

TrackTarget point_target(const Vec3& p) {
  TrackTarget t;
  t.kind = TrackTarget::Kind::kPoint;
  t.point = p;
  return t;
}

TEST(SceneTracker, NearestAxisTakesTheObjectInTheMiddleOfTheImage) {
  // The middle object stands farther than the left one: nearest the axis is not nearest the sensor.
  const std::vector<SceneShape> shapes = {{SceneShape::kBox, Vec3(-0.6f, 1.7f, 0), Vec3(0.25f, 0.25f, 0.3f)},
                                          {SceneShape::kCylinder, Vec3(0, 2.4f, 0), Vec3(0.12f, 0, 0.35f)},
                                          {SceneShape::kSphere, Vec3(0.7f, 2.1f, 0), Vec3(0.15f, 0, 0)}};
  const SyntheticScene s = camera_frame(shapes, Vec3(0, 0, 1.3f), Vec3(0, 2.4f, 0.15f));
  SceneTracker tracker = make_tracker({});
  const TrackStep step = step_of(tracker, s.frame);
  EXPECT_EQ(step.objects, 3u);
  expect_is(step, s.truth[1]);
  EXPECT_TRUE(tracker.acquired());
  // Without a camera frame: the object nearest the sensor.
  Cloud no_camera = s.frame;
  no_camera.frame.reset();
  SceneTracker by_range = make_tracker({});
  expect_is(step_of(by_range, no_camera), s.truth[0]);
}

TEST(SceneTracker, PointAndBoxTargetsTakeTheirObject) {
  const SyntheticScene s = test::four_object_scene();
  // Inside the cylinder's box; beside the sphere (10 cm off its box); on the floor far from everything.
  SceneTracker in_box = make_tracker(point_target(Vec3(-0.15f, 2.3f, 0.2f)));
  expect_is(step_of(in_box, s.frame), s.truth[1]);
  SceneTracker beside = make_tracker(point_target(s.truth[2].max + Vec3(0.1f, 0, 0)));
  expect_is(step_of(beside, s.frame), s.truth[2]);
  SceneTracker far = make_tracker(point_target(Vec3(0, 0.5f, 0)));
  const TrackStep none = step_of(far, s.frame);
  EXPECT_FALSE(none.found);
  EXPECT_EQ(none.objects, 4u);
  EXPECT_NE(none.not_found.find("0.30 m"), std::string::npos) << none.not_found;
  EXPECT_FALSE(far.acquired());
  // A box 10 cm looser than the last object's, and one than the first's.
  for (size_t k : {size_t(3), size_t(0)}) {
    TrackTarget box;
    box.kind = TrackTarget::Kind::kBox;
    box.box_min = s.truth[k].min - Vec3::Constant(0.1f);
    box.box_max = s.truth[k].max + Vec3::Constant(0.1f);
    SceneTracker tracker = make_tracker(box);
    expect_is(step_of(tracker, s.frame), s.truth[k]);
  }
}

// A cylinder (the target) with a box 5 cm to its right, a sphere behind and a box to its left.
const std::vector<SceneShape> kGroup = {{SceneShape::kCylinder, Vec3(0, 1.8f, 0), Vec3(0.1f, 0, 0.4f)},
                                        {SceneShape::kBox, Vec3(0.25f, 1.8f, 0), Vec3(0.2f, 0.2f, 0.3f)},
                                        {SceneShape::kSphere, Vec3(-0.1f, 2.15f, 0), Vec3(0.12f, 0, 0)},
                                        {SceneShape::kBox, Vec3(-0.4f, 1.6f, 0), Vec3(0.2f, 0.15f, 0.25f)}};

// The camera circles the gap between the target and its neighbour, so either may be nearest the image's
// centre; the stream names the target by a point inside it. Followed by the seen surface, and by the seen
// box alone (no object ever shares enough cells).
TEST(SceneTracker, FollowsTheTargetRoundTheGroupNeverANeighbour) {
  const Vec3 centre(0.125f, 1.8f, 0.15f);
  TrackParams box_only;
  box_only.min_shared_cells = std::numeric_limits<size_t>::max();
  for (const TrackParams& params : {TrackParams{}, box_only}) {
    SCOPED_TRACE(params.min_shared_cells == box_only.min_shared_cells ? "by the seen box" : "by the seen surface");
    SceneTracker tracker = make_tracker(point_target(Vec3(0, 1.8f, 0.2f)), params);
    constexpr int kFrames = 10;
    for (int f = 0; f < kFrames; ++f) {
      SCOPED_TRACE("frame " + std::to_string(f));
      const float a = -0.5f * std::numbers::pi_v<float> + 2 * std::numbers::pi_v<float> * float(f) / kFrames;
      const Vec3 sensor = centre + Vec3(1.6f * std::cos(a), 1.6f * std::sin(a), 1.15f);
      const SyntheticScene s = camera_frame(kGroup, sensor, centre);
      const TrackStep step = step_of(tracker, s.frame);
      EXPECT_GE(step.objects, 3u);
      expect_is(step, s.truth[0]);
      // Its centroid within the cylinder's footprint: the box's lies 15 cm or more from its axis.
      EXPECT_LT((step.object.centroid - Vec3(0, 1.8f, step.object.centroid.z())).norm(), 0.1f);
    }
    EXPECT_LT(tracker.seen_bounds().max.x(), 0.12f);  // the box 5 cm to the right never joined what was seen
  }
}

TEST(SceneTracker, LosesTheTargetOutOfViewOrHiddenAndFindsItAgain) {
  // A sphere (the target) 5 cm behind a tall board that hides it from the front, a cylinder aside.
  const std::vector<SceneShape> shapes = {{SceneShape::kSphere, Vec3(0, 2.0f, 0), Vec3(0.1f, 0, 0)},
                                          {SceneShape::kBox, Vec3(0, 1.8f, 0), Vec3(0.5f, 0.1f, 0.6f)},
                                          {SceneShape::kCylinder, Vec3(-1.2f, 1.0f, 0), Vec3(0.12f, 0, 0.4f)}};
  const Vec3 centre(0, 2.0f, 0.1f);
  const std::vector<SyntheticScene> frames = {
      camera_frame(shapes, Vec3(1.6f, 2.2f, 1.2f), centre),     // from the right: found by the axis
      camera_frame(shapes, Vec3(0, 0, 1.3f), centre),           // from the front: hidden by the board
      camera_frame(shapes, Vec3(0, 0, 1.3f), Vec3(-1.2f, 1.f, 0.2f)),  // looking away: out of view
      camera_frame(shapes, Vec3(-1.6f, 2.2f, 1.2f), centre)};   // from the left: found again
  SceneTracker tracker = make_tracker({});
  std::vector<TrackStep> steps;
  for (const SyntheticScene& s : frames) steps.push_back(step_of(tracker, s.frame));
  expect_is(steps[0], frames[0].truth[0]);
  for (size_t k : {size_t(1), size_t(2)}) {
    SCOPED_TRACE("frame " + std::to_string(k));
    EXPECT_GE(steps[k].objects, 1u);  // the board or the cylinder is there to be mistaken for it
    EXPECT_FALSE(steps[k].found);
  }
  EXPECT_NE(steps[1].not_found.find("hidden"), std::string::npos) << steps[1].not_found;
  EXPECT_NE(steps[2].not_found.find("left the view"), std::string::npos) << steps[2].not_found;
  expect_is(steps[3], frames[3].truth[0]);
  // Deterministic: the same frames give the same steps.
  SceneTracker again = make_tracker({});
  for (size_t k = 0; k < frames.size(); ++k) {
    const TrackStep step = step_of(again, frames[k].frame);
    EXPECT_EQ(step.found, steps[k].found);
    EXPECT_EQ(step.object.indices, steps[k].object.indices);
    EXPECT_EQ(step.not_found, steps[k].not_found);
  }
}

// A still camera's frames repeat one surface with new noise each time: the first frame's cluster is fresh
// whole, and twenty more add a fraction of it, not twenty copies, the last ten less than the first ten.
TEST(SceneTracker, AStillCamerasFramesAddLittleAfterTheFirst) {
  const std::vector<SceneShape> shapes = {{SceneShape::kBox, Vec3(-0.4f, 2.0f, 0), Vec3(0.3f, 0.3f, 0.4f)},
                                          {SceneShape::kCylinder, Vec3(0.3f, 2.2f, 0), Vec3(0.12f, 0, 0.4f)}};
  SceneTracker tracker = make_tracker(point_target(Vec3(0.3f, 2.2f, 0.2f)));
  size_t first = 0, added = 0, added_late = 0;
  for (uint32_t k = 0; k < 21; ++k) {
    SyntheticScene s = test::render_scene(test::Room{3.f, 4.f, 2.f}, shapes, Vec3(0, 0, 1.3f), Vec3(0, 2.1f, 0.2f),
                                          320, 240, 0.004f, 100 + k);
    const TrackStep step = step_of(tracker, s.frame);
    ASSERT_TRUE(step.found) << step.not_found;
    EXPECT_LE(step.fresh.size(), step.object.points.size());
    if (k == 0) {
      EXPECT_EQ(step.fresh.size(), step.object.points.size());
      first = step.fresh.size();
    } else {
      added += step.fresh.size();
      if (k > 10) added_late += step.fresh.size();
    }
  }
  EXPECT_GT(first, 500u);
  EXPECT_GT(added, 0u);           // noise reaches cells the first frame did not
  EXPECT_LT(added, 2 * first);    // far from twenty copies
  EXPECT_LT(2 * added_late, added);  // and less and less: the surface's cells fill up
}

TEST(SceneTracker, BadTargetsAndParametersAreInvalidArguments) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<TrackTarget> targets(4);
  targets[0].kind = TrackTarget::Kind::kPoint, targets[0].point = Vec3(0, nan, 0);
  targets[1].kind = TrackTarget::Kind::kBox, targets[1].box_min = Vec3(0, 0, 1), targets[1].box_max = Vec3(1, 1, 0);
  targets[2].kind = TrackTarget::Kind::kBox, targets[2].box_max = Vec3(inf, 1, 1);
  targets[3].kind = TrackTarget::Kind(7);
  for (const TrackTarget& t : targets) {
    Expected<SceneTracker> tracker = SceneTracker::create(t);
    ASSERT_FALSE(tracker.ok());
    EXPECT_EQ(tracker.error().code, ErrorCode::kInvalidArgument);
  }
  for (auto bad : {+[](TrackParams& p) { p.point_radius_m = -0.1f; }, +[](TrackParams& p) { p.match_distance_m = 0; },
                   +[](TrackParams& p) { p.min_shared_fraction = 1.5; }, +[](TrackParams& p) { p.fuse_cell_m = 0; }, +[](TrackParams& p) { p.scene.cluster_tolerance_m = 0; }}) {
    TrackParams params;
    bad(params);
    Expected<SceneTracker> tracker = SceneTracker::create({}, params);
    ASSERT_FALSE(tracker.ok());
    EXPECT_EQ(tracker.error().code, ErrorCode::kInvalidArgument);
  }
}

TEST(SceneTracker, FramesWithoutObjectsAreStepsNotErrors) {
  const SyntheticScene room = camera_frame({}, Vec3(0, 0, 1.3f), Vec3(0, 2.f, 0));
  SceneTracker tracker = make_tracker({});
  for (const Cloud& frame : {Cloud{}, room.frame}) {
    const TrackStep step = step_of(tracker, frame);
    EXPECT_FALSE(step.found);
    EXPECT_EQ(step.objects, 0u);
    EXPECT_EQ(step.not_found, "no objects in the frame");
  }
  // Once found, an empty frame keeps what was seen: the target is found again after it.
  const SyntheticScene s = test::four_object_scene();
  expect_is(step_of(tracker, s.frame), s.truth[2]);
  EXPECT_FALSE(step_of(tracker, room.frame).found);
  EXPECT_TRUE(tracker.acquired());
  expect_is(step_of(tracker, s.frame), s.truth[2]);
}

}  // namespace
}  // namespace glimpse
