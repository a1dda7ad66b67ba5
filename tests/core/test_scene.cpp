// Scene segmentation: the objects of a frame once its floor, walls and table tops are removed, on frames
// made by hand (synthetic_scene.h) and on the real Kinect-class frames beside the repository.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "glimpse/geometry/scene.h"
#include "glimpse/io/files.h"
#include "glimpse/views/placement.h"
#include "synthetic_scene.h"

namespace glimpse {
namespace {

using test::SceneShape;
using test::SyntheticScene;

// The scene's object whose centroid lies nearest `centre`.
const SceneObject* nearest_object(const Scene& scene, const Vec3& centre) {
  const SceneObject* best = nullptr;
  for (const SceneObject& o : scene.objects)
    if (!best || (o.centroid - centre).norm() < (best->centroid - centre).norm()) best = &o;
  return best;
}

// Each true object found once, its box within tolerance_m of the truth, and nothing else.
void expect_objects_match(const Scene& scene, const std::vector<Bounds>& truth, float tolerance_m) {
  ASSERT_EQ(scene.objects.size(), truth.size());
  std::vector<const SceneObject*> matched;
  for (size_t k = 0; k < truth.size(); ++k) {
    SCOPED_TRACE("object " + std::to_string(k));
    const SceneObject* o = nearest_object(scene, truth[k].centre());
    ASSERT_NE(o, nullptr);
    EXPECT_EQ(std::count(matched.begin(), matched.end(), o), 0) << "two true objects share one found object";
    matched.push_back(o);
    // The floor's inliers take the foot: as high as its reach at the object's range (plane_distance_per_m2).
    EXPECT_LT((o->box_min - truth[k].min).head<2>().cwiseAbs().maxCoeff(), tolerance_m) << o->box_min.transpose();
    EXPECT_LT(std::abs(o->box_min.z() - truth[k].min.z()), 0.02f + 0.003f * o->range_m * o->range_m + 0.01f);
    EXPECT_LT((o->box_max - truth[k].max).cwiseAbs().maxCoeff(), tolerance_m) << o->box_max.transpose();
    EXPECT_EQ(o->points.size(), o->indices.size());
  }
}

TEST(SegmentScene, FindsEachObjectOnTheFloorAndNothingElse) {
  const SyntheticScene s = test::four_object_scene();
  Expected<Scene> scene = segment_scene(s.frame);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  const size_t finite = size_t(std::count_if(s.frame.points.begin(), s.frame.points.end(), [](const Vec3& p) { return p.allFinite(); }));
  EXPECT_EQ(scene->finite_points, finite);
  EXPECT_LT(finite, s.frame.points.size());  // the rays above the wall hit nothing
  ASSERT_GE(scene->planes.size(), 2u);  // the floor and the wall
  // The floor holds the most points; each normal faces the sensor (the floor's up, the wall's towards it).
  EXPECT_GT(scene->planes[0].normal.z(), 0.99f);
  EXPECT_LT(scene->planes[1].normal.y(), -0.99f);
  for (const Plane& p : scene->planes) EXPECT_GT(p.normal.dot(*s.frame.sensor) + p.offset, 0.f);
  EXPECT_TRUE(has_level_plane(*scene));
  Scene walls_only = *scene;
  walls_only.planes.erase(walls_only.planes.begin());
  EXPECT_FALSE(has_level_plane(walls_only));
  // An object as Classify takes it: its points, with the frame's sensor.
  const Cloud object = object_cloud(s.frame, scene->objects.front());
  EXPECT_EQ(object.points.size(), scene->objects.front().points.size());
  EXPECT_EQ(object.sensor, s.frame.sensor);
  expect_objects_match(*scene, s.truth, 0.03f);
  for (size_t k = 1; k < scene->objects.size(); ++k) EXPECT_LE(scene->objects[k - 1].range_m, scene->objects[k].range_m);
  // Every finite point is in at most one plane or object.
  std::vector<int> owners(s.frame.points.size(), 0);
  size_t in_planes = 0;
  for (const Plane& p : scene->planes) in_planes += p.inliers;
  size_t in_objects = 0;
  for (const SceneObject& o : scene->objects) {
    for (uint32_t i : o.indices) ++owners[i];
    in_objects += o.indices.size();
  }
  EXPECT_EQ(*std::max_element(owners.begin(), owners.end()), 1);
  EXPECT_LE(in_planes + in_objects, finite);
  EXPECT_GT(in_planes + in_objects, finite * 99 / 100);  // little is dropped: no remnants to speak of
  for (const SceneObject& o : scene->objects) {
    EXPECT_TRUE(std::is_sorted(o.indices.begin(), o.indices.end()));
    for (size_t k = 0; k < o.indices.size(); ++k) ASSERT_EQ(o.points[k], s.frame.points[o.indices[k]]);
    EXPECT_NEAR((o.centroid - *s.frame.sensor).norm(), o.range_m, 1e-4f);
  }
}

// Two boxes side by side, 5 cm apart: two objects, at full resolution too.
SyntheticScene two_boxes(float gap_m) {
  const float x = 0.1f + gap_m / 2;
  const std::vector<SceneShape> shapes = {{SceneShape::kBox, Vec3(-x, 1.5f, 0), Vec3(0.2f, 0.2f, 0.3f)},
                                          {SceneShape::kBox, Vec3(x, 1.5f, 0), Vec3(0.2f, 0.2f, 0.3f)}};
  return test::render_scene(test::Room{1.f, 2.5f, 1.f}, shapes, Vec3(0, 0, 1.3f), Vec3(0, 1.5f, 0), 320, 240);
}

TEST(SegmentScene, ObjectsFiveCentimetresApartStayTwo) {
  const SyntheticScene s = two_boxes(0.05f);
  for (float voxel : {0.01f, 0.f}) {
    SCOPED_TRACE(voxel);
    SceneParams params;
    params.voxel_m = voxel;
    Expected<Scene> scene = segment_scene(s.frame, params);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    expect_objects_match(*scene, s.truth, 0.03f);
  }
  // Touching boxes are one object: the clusters are Euclidean (no split by normals).
  Expected<Scene> one = segment_scene(two_boxes(0.f).frame);
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one->objects.size(), 1u);
}

// A table (a 1.2 x 0.8 m top 0.74 m up on four legs) by a cabinet, and, when `cup`, a cup (a box) on it.
SyntheticScene table_scene(bool cup) {
  using Shape = test::SceneShape;
  std::vector<Shape> shapes = {{Shape::kBox, Vec3(0, 2.2f, 0.70f), Vec3(1.2f, 0.8f, 0.04f)},
                               {Shape::kCylinder, Vec3(-0.55f, 1.85f, 0), Vec3(0.025f, 0, 0.70f)},
                               {Shape::kCylinder, Vec3(0.55f, 1.85f, 0), Vec3(0.025f, 0, 0.70f)},
                               {Shape::kCylinder, Vec3(-0.55f, 2.55f, 0), Vec3(0.025f, 0, 0.70f)},
                               {Shape::kCylinder, Vec3(0.55f, 2.55f, 0), Vec3(0.025f, 0, 0.70f)},
                               {Shape::kBox, Vec3(1.2f, 2.4f, 0), Vec3(0.4f, 0.4f, 0.5f)}};
  if (cup) shapes.push_back({Shape::kBox, Vec3(0.1f, 2.1f, 0.74f), Vec3(0.12f, 0.12f, 0.15f)});
  return test::render_scene(test::Room{}, shapes, Vec3(0.2f, 0, 1.6f), Vec3(0.2f, 2.2f, 0.4f));
}

TEST(SegmentScene, ABareTableTopIsTheTablesFaceAndATopWithACupOnItIsRemoved) {
  Expected<Scene> bare = segment_scene(table_scene(false).frame);
  ASSERT_TRUE(bare.ok()) << bare.error().message;
  // The table, its top and front legs (the top hides the back legs' upper half: their feet are apart),
  // and the cabinet.
  const auto table = std::find_if(bare->objects.begin(), bare->objects.end(),
                                  [](const SceneObject& o) { return o.box_max.x() - o.box_min.x() > 1.f; });
  ASSERT_NE(table, bare->objects.end());
  EXPECT_EQ(std::count_if(bare->objects.begin(), bare->objects.end(),
                          [](const SceneObject& o) { return o.points.size() > 2000; }),
            2);
  EXPECT_NEAR(table->box_max.x() - table->box_min.x(), 1.2f, 0.05f);
  EXPECT_NEAR(table->box_max.z(), 0.74f, 0.02f);
  EXPECT_LT(table->box_min.z(), 0.1f);  // its legs stand on the floor

  // With a cup on it, the top is a table top holding an object: removed, the cup found alone.
  Expected<Scene> laid = segment_scene(table_scene(true).frame);
  ASSERT_TRUE(laid.ok()) << laid.error().message;
  const bool top_removed = std::any_of(laid->planes.begin(), laid->planes.end(), [](const Plane& p) {
    return p.normal.z() > 0.99f && std::abs(-p.offset / p.normal.z() - 0.74f) < 0.03f;
  });
  EXPECT_TRUE(top_removed);
  const bool cup_alone = std::any_of(laid->objects.begin(), laid->objects.end(), [](const SceneObject& o) {
    return (o.box_max - o.box_min).head<2>().maxCoeff() < 0.2f && o.box_min.z() > 0.72f;
  });
  EXPECT_TRUE(cup_alone);
}

TEST(SegmentScene, SameSceneWhateverTheThreadCount) {
  const SyntheticScene s = test::four_object_scene(3);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  Expected<Scene> serial = segment_scene(s.frame);
  omp_set_num_threads(std::max(2, threads));
  Expected<Scene> parallel = segment_scene(s.frame);
  omp_set_num_threads(threads);
  ASSERT_TRUE(serial.ok() && parallel.ok());
  ASSERT_EQ(serial->planes.size(), parallel->planes.size());
  for (size_t k = 0; k < serial->planes.size(); ++k) {
    EXPECT_EQ(serial->planes[k].normal, parallel->planes[k].normal);
    EXPECT_EQ(serial->planes[k].offset, parallel->planes[k].offset);
    EXPECT_EQ(serial->planes[k].inliers, parallel->planes[k].inliers);
  }
  ASSERT_EQ(serial->objects.size(), parallel->objects.size());
  for (size_t k = 0; k < serial->objects.size(); ++k) EXPECT_EQ(serial->objects[k].indices, parallel->objects[k].indices);
}

TEST(SegmentScene, KeepsTheNearestObjectsAndDropsSmallOnes) {
  const SyntheticScene s = test::four_object_scene();
  SceneParams params;
  params.max_objects = 2;
  Expected<Scene> nearest = segment_scene(s.frame, params);
  Expected<Scene> all = segment_scene(s.frame);
  ASSERT_TRUE(nearest.ok() && all.ok());
  ASSERT_EQ(nearest->objects.size(), 2u);
  EXPECT_EQ(nearest->objects[0].indices, all->objects[0].indices);
  EXPECT_EQ(nearest->objects[1].indices, all->objects[1].indices);
  // A threshold above the smallest object's points drops it alone.
  size_t smallest = std::numeric_limits<size_t>::max();
  for (const SceneObject& o : all->objects) smallest = std::min(smallest, o.indices.size());
  params = SceneParams{};
  params.min_object_points = smallest + 1;
  params.reference_density_per_deg2 = 0;  // the threshold as given, not scaled to the 320 x 240 frame
  Expected<Scene> fewer = segment_scene(s.frame, params);
  ASSERT_TRUE(fewer.ok());
  EXPECT_EQ(fewer->objects.size(), all->objects.size() - 1);
}

// A frame's objects need points in proportion to its density: the same room at 640 x 480 and 320 x 240
// gives the same objects with the default parameters; 320 x 240 with the counts of 640 x 480 as given loses
// the smaller ones.
TEST(SegmentScene, ASparserFrameAsksItsObjectsForFewerPoints) {
  const std::vector<SceneShape> shapes = {{SceneShape::kBox, Vec3(-0.5f, 2.0f, 0), Vec3(0.2f, 0.2f, 0.3f)},
                                          {SceneShape::kCylinder, Vec3(0.3f, 1.8f, 0), Vec3(0.08f, 0, 0.25f)},
                                          {SceneShape::kSphere, Vec3(0.9f, 2.3f, 0), Vec3(0.1f, 0, 0)}};
  const test::Room room{2.f, 3.f, 1.5f};
  const SyntheticScene full = test::render_scene(room, shapes, Vec3(0, 0, 1.3f), Vec3(0.2f, 2.f, 0), 640, 480);
  const SyntheticScene quarter = test::render_scene(room, shapes, Vec3(0, 0, 1.3f), Vec3(0.2f, 2.f, 0), 320, 240);
  Expected<Scene> a = segment_scene(full.frame), b = segment_scene(quarter.frame);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_GT(a->density_per_deg2, 100);  // 640 x 480 over 57 x 43 degrees: about 109 on the axis
  EXPECT_LT(a->density_per_deg2, 140);
  EXPECT_NEAR(b->density_per_deg2, a->density_per_deg2 / 4, 0.1 * a->density_per_deg2);
  EXPECT_EQ(a->min_object_points, 1000u);
  EXPECT_NEAR(double(b->min_object_points), 1000 * b->density_per_deg2 / 80, 1);
  expect_objects_match(*a, full.truth, 0.03f);
  expect_objects_match(*b, quarter.truth, 0.03f);
  SceneParams as_given;
  as_given.reference_density_per_deg2 = 0;
  Expected<Scene> c = segment_scene(quarter.frame, as_given);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->min_object_points, 1000u);
  EXPECT_LT(c->objects.size(), quarter.truth.size());
}

// Below the reference density the object's points scale with the density and the clustering's range term
// with the points' spacing; the 3 cm that parts objects stays; at or above it nothing changes.
TEST(SegmentScene, AtDensityScalesCountsAndTheRangeTermBelowTheReference) {
  SceneParams p;
  const SceneParams kinect = at_density(p, 84);
  EXPECT_EQ(kinect.min_object_points, p.min_object_points);
  EXPECT_EQ(kinect.cluster_tolerance_per_m2, p.cluster_tolerance_per_m2);
  const SceneParams quarter = at_density(p, p.reference_density_per_deg2 / 4);
  EXPECT_EQ(quarter.min_object_points, p.min_object_points / 4);
  EXPECT_FLOAT_EQ(quarter.cluster_tolerance_per_m2, 2 * p.cluster_tolerance_per_m2);
  EXPECT_EQ(quarter.cluster_tolerance_m, p.cluster_tolerance_m);
  EXPECT_EQ(at_density(p, 0.5).min_object_points, 20u);  // never below 20
  p.min_object_points = 5;
  EXPECT_EQ(at_density(p, 1).min_object_points, 5u);      // nor above what was asked
  p.reference_density_per_deg2 = 0;
  EXPECT_EQ(at_density(p, 10).min_object_points, 5u);     // off: as given
}

TEST(SegmentScene, EmptyFramesAndBadParameters) {
  Expected<Scene> empty = segment_scene(Cloud{});
  ASSERT_TRUE(empty.ok()) << empty.error().message;
  EXPECT_TRUE(empty->objects.empty());
  EXPECT_TRUE(empty->planes.empty());
  Cloud missing;
  missing.points.assign(1000, Vec3::Constant(std::numeric_limits<float>::quiet_NaN()));
  Expected<Scene> none = segment_scene(missing);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->finite_points, 0u);
  EXPECT_TRUE(none->objects.empty());
  const Cloud frame = test::four_object_scene().frame;
  for (auto bad : {+[](SceneParams& p) { p.voxel_m = -0.01f; }, +[](SceneParams& p) { p.plane_distance_m = 0; },
                   +[](SceneParams& p) { p.cluster_tolerance_m = 0; }, +[](SceneParams& p) { p.min_object_points = p.max_object_points + 1; }}) {
    SceneParams params;
    bad(params);
    Expected<Scene> scene = segment_scene(frame, params);
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().code, ErrorCode::kInvalidArgument);
  }
}

// ---- real frames (../shared/data/real-scenes: its README gives each frame's table / desk normal) ----

std::string real_scenes_dir() {
  if (const char* env = std::getenv("GLIMPSE_REAL_SCENES_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/real-scenes";
}

// An object standing on a support plane: its lowest point within 4 cm of the plane (the plane's 2 cm of
// inliers take the object's foot), and its height above it.
struct Standing {
  const SceneObject* object;
  float height_m;
};
std::vector<Standing> standing_on(const Scene& scene, const Vec3& up) {
  const Plane* support = nullptr;
  for (const Plane& p : scene.planes)
    if (std::abs(p.normal.dot(up)) > std::cos(5.f * std::numbers::pi_v<float> / 180.f)) {
      support = &p;
      break;
    }
  std::vector<Standing> out;
  if (!support) return out;
  const float sign = support->normal.dot(up) > 0 ? 1.f : -1.f;  // heights along up
  for (const SceneObject& o : scene.objects) {
    float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
    for (const Vec3& p : o.points) {
      const float h = sign * (support->normal.dot(p) + support->offset);
      low = std::min(low, h), high = std::max(high, h);
    }
    if (low < 0.04f) out.push_back({&o, high});
  }
  return out;
}

// The frame levelled by the floor or table it shows, +z up, as `glimpse scene --up floor` sends it.
Cloud levelled(Cloud frame) {
  const Expected<Vec3> up = floor_up(frame);
  EXPECT_TRUE(up.ok()) << up.error().message;
  if (!up) return frame;
  const Eigen::Matrix3f r = upright_rotation(*up);
  for (Vec3& p : frame.points) p = r * p;
  if (frame.sensor) *frame.sensor = r * *frame.sensor;
  return frame;
}

void print_scene(const std::string& name, const Scene& scene, const std::vector<Standing>& standing) {
  std::printf("%s: %zu planes, %zu objects\n", name.c_str(), scene.planes.size(), scene.objects.size());
  for (const SceneObject& o : scene.objects) {
    const Vec3 e = o.box_max - o.box_min;
    float height = -1;
    for (const Standing& s : standing)
      if (s.object == &o) height = s.height_m;
    std::printf("  %6zu points, box %.2f x %.2f x %.2f m, range %.2f m, height above the support %s\n", o.points.size(),
                e.x(), e.y(), e.z(), o.range_m, height < 0 ? "(not on it)" : (std::to_string(height).substr(0, 5) + " m").c_str());
  }
}

TEST(SegmentScene, RealTabletopHasThreeBottlesOnTheTable) {
  const std::string dir = real_scenes_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "real scenes not found at " << dir << " (set GLIMPSE_REAL_SCENES_DIR)";
  Expected<Cloud> read = read_cloud(dir + "/tabletop_milk_bleach_detergent.pcd");
  ASSERT_TRUE(read.ok()) << read.error().message;
  for (const bool level : {false, true}) {  // in the camera's coordinates, and levelled (+z up)
    SCOPED_TRACE(level ? "levelled" : "camera coordinates");
    const Cloud frame = level ? levelled(*read) : *read;
    Expected<Scene> scene = segment_scene(frame);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const std::vector<Standing> on_table =
        standing_on(*scene, level ? Vec3::UnitZ() : Vec3(0.005f, -0.821f, -0.571f).normalized());
    print_scene(level ? "tabletop, levelled" : "tabletop", *scene, on_table);
    std::vector<const SceneObject*> bottles;  // 0.20-0.25 m tall by the README; a cap or handle adds a little
    for (const Standing& s : on_table)
      if (s.height_m > 0.18f && s.height_m < 0.35f) bottles.push_back(s.object);
    ASSERT_EQ(bottles.size(), 3u);
    for (const SceneObject* b : bottles) {
      EXPECT_LT(b->range_m, 1.f);  // the three stand in front of the camera, the rest of the table beyond them
      EXPECT_GT(b->points.size(), 5000u);
      EXPECT_LT((b->box_max - b->box_min).maxCoeff(), 0.35f);
    }
    size_t near = 0;
    for (const SceneObject& o : scene->objects) near += o.range_m < 1.f;
    EXPECT_EQ(near, 3u);  // nothing else within 1 m: no fragment of a bottle, no remnant of the table
  }
}

TEST(SegmentScene, RealDeskFramesPartTheLaptopFromTheBox) {
  const std::string dir = real_scenes_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "real scenes not found at " << dir << " (set GLIMPSE_REAL_SCENES_DIR)";
  const Vec3 desk_up = Vec3(0.072f, -0.692f, -0.718f).normalized();
  for (int k = 0; k < 3; ++k) {
    const std::string name = "desk_laptop_box_frame" + std::to_string(k) + ".pcd";
    SCOPED_TRACE(name);
    Expected<Cloud> read = read_cloud(dir + "/" + name);
    ASSERT_TRUE(read.ok()) << read.error().message;
    // In the camera's coordinates, and levelled (+z up) as `glimpse scene --up floor` sends it. Levelled,
    // frame 2's laptop and box come as one: they touch within 1.5 cm there (touching objects are one).
    for (const bool level : {false, true}) {
      if (level && k == 2) continue;
      SCOPED_TRACE(level ? "levelled" : "camera coordinates");
      const Cloud frame = level ? levelled(*read) : *read;
      Expected<Scene> scene = segment_scene(frame);
      ASSERT_TRUE(scene.ok()) << scene.error().message;
      // A real 640 x 480 Kinect's frame (about 84 points per square degree) keeps the default counts.
      EXPECT_GE(scene->density_per_deg2, SceneParams{}.reference_density_per_deg2);
      EXPECT_EQ(scene->min_object_points, SceneParams{}.min_object_points);
      const std::vector<Standing> on_desk = standing_on(*scene, level ? Vec3::UnitZ() : desk_up);
      print_scene(level ? name + ", levelled" : name, *scene, on_desk);
      // The desk's front holds the laptop (open, its screen up to ~0.22 m above the desk) and the box
      // (~0.08 m tall): two large objects, apart.
      std::vector<Standing> large;
      for (const Standing& s : on_desk)
        if (s.object->range_m < 1.1f && s.object->points.size() > 2000) large.push_back(s);
      ASSERT_EQ(large.size(), 2u);
      const Standing& laptop = large[0].height_m > large[1].height_m ? large[0] : large[1];
      const Standing& box = &laptop == &large[0] ? large[1] : large[0];
      EXPECT_GT(laptop.height_m, 0.15f);
      EXPECT_LT(laptop.height_m, 0.30f);
      EXPECT_GT(box.height_m, 0.05f);
      EXPECT_LT(box.height_m, 0.12f);
      EXPECT_GT(laptop.object->points.size(), box.object->points.size());
      EXPECT_GT((laptop.object->centroid - box.object->centroid).norm(), 0.2f);
    }
  }
}

TEST(SegmentScene, RealFrameTwiceIsTheSameScene) {
  const std::string dir = real_scenes_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "real scenes not found at " << dir << " (set GLIMPSE_REAL_SCENES_DIR)";
  Expected<Cloud> frame = read_cloud(dir + "/desk_laptop_box_frame0.pcd");
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  Expected<Scene> a = segment_scene(*frame), b = segment_scene(*frame);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->objects.size(), b->objects.size());
  for (size_t k = 0; k < a->objects.size(); ++k) EXPECT_EQ(a->objects[k].indices, b->objects[k].indices);
}

}  // namespace
}  // namespace glimpse
