// Which removed planes stay removed in a scene: the floor and the walls bound the room, a plane through an
// object's broad face goes back to the object; pieces of one object over one another, or either side of a
// nearer object, join; the floor's remnants are no objects. Frames made by hand (synthetic_scene.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "glimpse/geometry/scene.h"
#include "synthetic_scene.h"

namespace glimpse {
namespace {

using test::SceneShape;

bool has_wall(const Scene& scene) {
  return std::any_of(scene.planes.begin(), scene.planes.end(), [](const Plane& p) { return p.normal.y() < -0.95f; });
}

// A person-sized box facing the camera 1.6 m away, its front 0.5 x 1.7 m: a broad plane RANSAC removes
// before the box's sides, with the wall 4 m away behind it.
TEST(ScenePlanes, ABroadFaceBeforeTheWallStaysWithItsObject) {
  const test::SyntheticScene s = test::render_scene(test::Room{}, {{SceneShape::kBox, Vec3(0.f, 1.6f, 0), Vec3(0.5f, 0.25f, 1.7f)}},
                                                    Vec3(0.3f, 0, 1.3f), Vec3(0, 2.f, 0.8f));
  Expected<Scene> scene = segment_scene(s.frame);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_TRUE(has_level_plane(*scene));
  EXPECT_TRUE(has_wall(*scene));  // nothing lies behind the wall: it stays removed
  ASSERT_EQ(scene->objects.size(), 1u);
  const SceneObject& box = scene->objects.front();
  EXPECT_LT((box.box_max - s.truth[0].max).cwiseAbs().maxCoeff(), 0.03f) << box.box_max.transpose();
  EXPECT_LT((box.box_min - s.truth[0].min).head<2>().cwiseAbs().maxCoeff(), 0.03f) << box.box_min.transpose();
  EXPECT_NEAR(box.box_min.z(), s.truth[0].min.z(), 0.03f);  // the frame cuts its foot
  // Its front is most of what the camera sees of it.
  size_t front = 0;
  for (const Vec3& p : box.points) front += std::abs(p.y() - (1.6f - 0.125f)) < 0.02f;
  EXPECT_GT(front, box.points.size() / 2);
}

// Two 50 cm boxes with the same footprint, one on the floor and one above it: pieces of one object that
// a view parts (an animal's body over its legs) when the gap between them is at most 60 cm and no table
// top lies in it; two objects when the gap is wider, or when they stand side by side.
TEST(ScenePlanes, PiecesOverOneAnotherJoinAcrossAGapOfUpTo60Centimetres) {
  auto frame = [](float upper_base_z, float upper_x) {
    return test::render_scene(test::Room{},
                              {{SceneShape::kBox, Vec3(0.f, 2.f, 0), Vec3(0.4f, 0.3f, 0.5f)},
                               {SceneShape::kBox, Vec3(upper_x, 2.f, upper_base_z), Vec3(0.4f, 0.3f, 0.5f)}},
                              Vec3(0, 0, 1.3f), Vec3(0, 2.f, 0.7f));
  };
  const test::SyntheticScene stacked = frame(0.75f, 0.f);  // a 25 cm gap
  Expected<Scene> one = segment_scene(stacked.frame);
  ASSERT_TRUE(one.ok()) << one.error().message;
  ASSERT_EQ(one->objects.size(), 1u);
  EXPECT_NEAR(one->objects[0].box_max.z(), stacked.truth[1].max.z(), 0.03f);
  EXPECT_LT(one->objects[0].box_min.z(), 0.06f);

  Expected<Scene> far_apart = segment_scene(frame(1.3f, 0.f).frame);  // an 80 cm gap
  ASSERT_TRUE(far_apart.ok());
  EXPECT_EQ(far_apart->objects.size(), 2u);
  Expected<Scene> side_by_side = segment_scene(frame(0.f, 0.6f).frame);  // 20 cm apart on the floor
  ASSERT_TRUE(side_by_side.ok());
  EXPECT_EQ(side_by_side->objects.size(), 2u);
}

// A 5 cm slab on the floor lies within twice the floor's reach: the floor's remnant (as its noise beyond
// the inlier distance is), not an object. The box beside it is.
TEST(ScenePlanes, ASlabWithinTheFloorsNoiseIsItsRemnant) {
  const test::SyntheticScene s = test::render_scene(test::Room{},
                                                    {{SceneShape::kBox, Vec3(-0.4f, 2.f, 0), Vec3(0.6f, 0.6f, 0.05f)},
                                                     {SceneShape::kBox, Vec3(0.5f, 2.f, 0), Vec3(0.3f, 0.3f, 0.3f)}},
                                                    Vec3(0, 0, 1.3f), Vec3(0, 2.f, 0));
  Expected<Scene> scene = segment_scene(s.frame);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->objects.size(), 1u);
  EXPECT_GT(scene->objects[0].centroid.x(), 0.3f);

  SceneParams keep_remnants;
  keep_remnants.max_remnant_share = 1.1;  // more than every point: nothing is a remnant
  Expected<Scene> kept = segment_scene(s.frame, keep_remnants);
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->objects.size(), 2u);
}

// A 1.2 m wide cabinet 2.6 m away with a 20 cm post before its middle: the post parts it into two pieces
// whose gap lies behind the post, so they are one object. Two boxes 60 cm apart behind the same post
// stay two: the camera sees the floor between them.
TEST(ScenePlanes, PiecesPartedByANearerObjectJoin) {
  const Vec3 camera(0, 0, 1.0f), target(0, 2.4f, 0.4f);
  const SceneShape post{SceneShape::kBox, Vec3(0, 1.6f, 0), Vec3(0.2f, 0.2f, 1.0f)};
  const test::SyntheticScene parted =
      test::render_scene(test::Room{}, {post, {SceneShape::kBox, Vec3(0, 2.6f, 0), Vec3(1.2f, 0.3f, 0.6f)}}, camera, target);
  Expected<Scene> scene = segment_scene(parted.frame);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->objects.size(), 2u);
  const SceneObject& cabinet = scene->objects[1];  // the farther
  EXPECT_LT((cabinet.box_min - parted.truth[1].min).head<2>().cwiseAbs().maxCoeff(), 0.03f) << cabinet.box_min.transpose();
  EXPECT_LT((cabinet.box_max - parted.truth[1].max).cwiseAbs().maxCoeff(), 0.03f) << cabinet.box_max.transpose();

  const test::SyntheticScene apart = test::render_scene(
      test::Room{},
      {post, {SceneShape::kBox, Vec3(-0.5f, 2.6f, 0), Vec3(0.4f, 0.3f, 0.6f)}, {SceneShape::kBox, Vec3(0.5f, 2.6f, 0), Vec3(0.4f, 0.3f, 0.6f)}},
      camera, target);
  Expected<Scene> two = segment_scene(apart.frame);
  ASSERT_TRUE(two.ok());
  EXPECT_EQ(two->objects.size(), 3u);
}

}  // namespace
}  // namespace glimpse
