// Synthetic scenes (glimpse/lab/scenes.h): box overlap and matching, labelling a hand-made scene against
// where its boxes are, its free-standing objects found by segment_scene, a small run on the zoo with a
// tiny model whose figures must agree with their counts, and segment_scene's detection on scenes of
// sources its parameters were not chosen on, against floors just under the measured figures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "glimpse/lab/evaluation.h"
#include "glimpse/lab/scenes.h"

namespace glimpse {
namespace {

Bounds box(float x0, float y0, float z0, float x1, float y1, float z1) { return {Vec3(x0, y0, z0), Vec3(x1, y1, z1)}; }

// ---- boxes ------------------------------------------------------------------------------------------

TEST(SceneBoxes, IouOfIdenticalBoxesIsOneOfDisjointOnesZero) {
  const Bounds a = box(0, 0, 0, 1, 1, 1);
  EXPECT_DOUBLE_EQ(box_iou(a, a), 1.0);
  EXPECT_DOUBLE_EQ(box_iou(box(0, 0, 0, 1, 1, 0), box(0, 0, 0, 1, 1, 0)), 1.0);  // flat, identical
  EXPECT_DOUBLE_EQ(box_iou(a, box(2, 0, 0, 3, 1, 1)), 0.0);
  EXPECT_DOUBLE_EQ(box_iou(a, box(1, 0, 0, 2, 1, 1)), 0.0);                      // sharing a face
  EXPECT_NEAR(box_iou(a, box(0.5f, 0, 0, 1.5f, 1, 1)), 1.0 / 3.0, 1e-6);        // half of each overlaps
  EXPECT_NEAR(box_iou(a, box(0, 0, 0, 2, 2, 2)), 1.0 / 8.0, 1e-6);              // one inside the other
  EXPECT_FLOAT_EQ(box_gap(a, box(2, 0, 0, 3, 1, 1)), 1.f);
  EXPECT_FLOAT_EQ(box_gap(a, box(0.5f, 0.5f, 0, 3, 1, 1)), 0.f);
  EXPECT_NEAR(box_gap(a, box(2, 2, 0, 3, 3, 1)), std::sqrt(2.f), 1e-6);
}

TEST(SceneBoxes, MatchingIsOneToOneHighestIouFirst) {
  const Bounds a = box(0, 0, 0, 1, 1, 1), near_a = box(0.1f, 0, 0, 1.1f, 1, 1), far = box(5, 5, 0, 6, 6, 1);
  // Both detections overlap truth 0; the better one takes it, the other is left unmatched.
  std::vector<BoxMatch> m = match_boxes({near_a, a, far}, {a}, 0.5);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].detection, 1);
  EXPECT_EQ(m[0].truth, 0);
  EXPECT_DOUBLE_EQ(m[0].iou, 1.0);
  // Two truths, two detections: each detection its own truth; below min_iou nothing matches.
  m = match_boxes({far, near_a}, {a, far}, 0.5);
  ASSERT_EQ(m.size(), 2u);
  for (const BoxMatch& x : m) EXPECT_EQ(x.detection == 0 ? 1 : 0, x.truth);
  EXPECT_TRUE(match_boxes({box(0.6f, 0, 0, 1.6f, 1, 1)}, {a}, 0.5).empty());
  EXPECT_TRUE(match_boxes({}, {a}, 0.5).empty());
}

// ---- a hand-made scene ---------------------------------------------------------------------------------

Mesh box_mesh(const Bounds& b) {
  Mesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back(k & 1 ? b.max.x() : b.min.x(), k & 2 ? b.max.y() : b.min.y(), k & 4 ? b.max.z() : b.min.z());
  const int faces[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                            {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  for (const auto& f : faces) m.faces.emplace_back(f[0], f[1], f[2]);
  return m;
}

void append(Mesh& into, const Mesh& m) {
  const int offset = int(into.vertices.size());
  into.vertices.insert(into.vertices.end(), m.vertices.begin(), m.vertices.end());
  for (const Eigen::Vector3i& f : m.faces) into.faces.push_back(f + Eigen::Vector3i::Constant(offset));
}

// Two boxes 0.65 m apart on a floor, a wall 1 m behind them, the camera 2 m away and 25 deg above.
RoomScene two_boxes(std::vector<EvalObject>& pool) {
  RoomScene scene;
  scene.seed = 5;
  const Bounds boxes[] = {box(-0.7f, -0.2f, 0, -0.3f, 0.2f, 0.6f), box(0.35f, -0.25f, 0, 0.65f, 0.25f, 0.8f)};
  for (size_t k = 0; k < 2; ++k) {
    pool.push_back({k ? "table" : "chair", std::to_string(k), box_mesh(boxes[k]), "hand"});
    scene.objects.push_back({k, box_mesh(boxes[k]), boxes[k]});
  }
  scene.floor = box_mesh(box(-4, -4, -0.01f, 4, 1, 0));
  scene.room = scene.floor;
  append(scene.room, box_mesh(box(-4, 1, 0, 4, 1.01f, 2.5f)));
  scene.pose = orbit_pose(Vec3(0, 0, 0.4f), -90.f, 25.f, 2.f);
  Mesh all = scene.room;
  for (const PlacedObject& o : scene.objects) append(all, o.mesh);
  auto cast = RayScene::build(all);
  EXPECT_TRUE(cast.ok());
  if (cast.ok()) scene.frame = depth_camera_scan(*cast, scene.pose, DepthCameraParams{}, scene.seed);
  return scene;
}

Bounds grown(const Bounds& b, float m) { return {b.min - Vec3::Constant(m), b.max + Vec3::Constant(m)}; }
bool inside(const Bounds& b, const Vec3& p) { return (p.array() >= b.min.array()).all() && (p.array() <= b.max.array()).all(); }

TEST(SceneTruth, LabelsEveryPointOfEachBoxWithItAndTheRoomWithNone) {
  std::vector<EvalObject> pool;
  const RoomScene scene = two_boxes(pool);
  ASSERT_GT(scene.frame.points.size(), 10000u);
  auto truth = scene_truth(scene, SceneLayout{});
  ASSERT_TRUE(truth.ok()) << truth.error().message;
  ASSERT_EQ(truth->size(), 2u);
  std::vector<int> label(scene.frame.points.size(), -1);
  for (size_t k = 0; k < 2; ++k) {
    const ObjectView& v = (*truth)[k];
    EXPECT_GT(v.indices.size(), 1000u) << k;
    EXPECT_NEAR(v.visible, 1.0, 0.05) << k;  // nothing hides it: as many points as alone
    EXPECT_EQ(v.kind, SceneKind::kFree) << k;
    EXPECT_GT(v.alone.points.size(), 1000u);
    EXPECT_TRUE(v.alone.sensor.has_value());
    for (uint32_t i : v.indices) label[i] = int(k);
  }
  // The brute-force reference: above the floor and in front of the wall only the boxes stand, so every
  // such point is its box's; every labelled point lies on (within the depth noise of) its own box.
  size_t checked = 0;
  for (size_t i = 0; i < label.size(); ++i) {
    const Vec3& p = scene.frame.points[i];
    if (label[i] >= 0) {
      EXPECT_TRUE(inside(grown(scene.objects[size_t(label[i])].box, 0.05f), p)) << i;
    }
    if (p.z() > 0.05f && p.y() < 0.9f) {
      ++checked;
      EXPECT_GE(label[i], 0) << "point " << i << " above the floor, off the wall, unlabelled";
    }
  }
  EXPECT_GT(checked, 2000u);
}

TEST(SceneTruth, FreeStandingObjectsAreAllDetected) {
  std::vector<EvalObject> pool;
  const RoomScene scene = two_boxes(pool);
  auto truth = scene_truth(scene, SceneLayout{});
  ASSERT_TRUE(truth.ok());
  ScenesParams params;
  auto segmented = segment_scene(scene.frame, params.segmentation);
  ASSERT_TRUE(segmented.ok()) << segmented.error().message;
  const SceneOutcome out = score_scene(scene, *truth, *segmented, pool, params);
  ASSERT_EQ(out.truth.size(), 2u);
  for (const TruthOutcome& t : out.truth) {
    EXPECT_GE(t.detection, 0) << t.category << ": " << t.miss;
    EXPECT_GE(t.iou, 0.5) << t.category;
    EXPECT_TRUE(t.miss.empty());
  }
  EXPECT_EQ(out.truth[0].category, "chair");
}

// ---- a run on the zoo -------------------------------------------------------------------------------------

// A tiny model of the zoo: 3 objects per category, 3 views of 2000 points, no sensor views.
const Model& tiny_zoo_model() {
  static const Model model = [] {
    EvalParams p;
    p.points_per_object = 2000;
    p.views_per_object = 3;
    p.methods = {MethodId::kUSH, MethodId::kVFH, MethodId::kSize, MethodId::kFusion};
    p.seed = 7;
    std::vector<EvalObject> objects = zoo_objects(3, 7);
    for (EvalObject& o : objects) o.role = EvalRole::kTrainOnly;
    auto m = train_lab_model(objects, p);
    EXPECT_TRUE(m.ok()) << m.error().message;
    return m.ok() ? std::move(*m) : Model{};
  }();
  return model;
}

ScenesParams small_run() {
  ScenesParams p;
  p.scenes = 3;
  p.seed = 11;
  p.layout.max_objects = 4;
  return p;
}

TEST(RunScenes, RejectsBadInput) {
  EXPECT_FALSE(run_scenes({}, nullptr, small_run()).ok());
  ScenesParams none = small_run();
  none.scenes = 0;
  EXPECT_FALSE(run_scenes(zoo_objects(1, 3), nullptr, none).ok());
  SceneLayout backwards;
  backwards.min_objects = 5, backwards.max_objects = 2;
  EXPECT_FALSE(make_room_scene(zoo_objects(1, 3), backwards, 1).ok());
}

TEST(RunScenes, FiguresAgreeWithTheirCounts) {
  const std::vector<EvalObject> pool = zoo_objects(2, 1234);  // not the model's zoo (seed 7)
  auto r = run_scenes(pool, &tiny_zoo_model(), small_run());
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->scenes.size(), 3u);
  const ScenesSummary s = summarise(*r);
  size_t visible = 0, found = 0, detections = 0, classified = 0;
  for (const SceneOutcome& scene : r->scenes) {
    EXPECT_GE(scene.truth.size(), 1u);
    EXPECT_LE(scene.truth.size(), 4u);
    EXPECT_GT(scene.segment_ms, 0.0);
    detections += scene.detections.size();
    for (const TruthOutcome& t : scene.truth) {
      if (t.visible < r->params.min_visible) continue;
      ++visible;
      EXPECT_GT(t.points, 0u) << "an object at least 30 % visible has points";
      if (t.detection < 0) {
        EXPECT_FALSE(t.miss.empty());
        continue;
      }
      ++found;
      EXPECT_GE(t.iou, 0.5);
      EXPECT_EQ(scene.detections[size_t(t.detection)].truth, &t - scene.truth.data());
      classified += t.scene.decided;
      EXPECT_TRUE(t.alone.decided);
    }
  }
  EXPECT_GT(visible, 0u);
  EXPECT_EQ(s.recall.total, visible);
  EXPECT_EQ(s.recall.correct, found);
  EXPECT_EQ(s.precision.correct, found);  // each found object is one right detection
  EXPECT_EQ(s.precision.total + s.ignored_detections, detections);
  EXPECT_EQ(s.scene_closest.total, found);
  EXPECT_EQ(classified, found);
  for (const Tally& t : {s.recall, s.precision, s.scene_closest, s.alone_closest, s.scene_accepted, s.alone_accepted}) {
    EXPECT_LE(t.correct, t.total);
    EXPECT_GE(t.percent(), 0.0);
    EXPECT_LE(t.percent(), 100.0);
  }
  EXPECT_LE(s.scene_accepted.correct, s.scene_closest.correct);
  size_t by_kind = 0;
  for (const Tally& t : s.recall_by_kind) by_kind += t.total;
  EXPECT_EQ(by_kind, s.recall.total);
  EXPECT_GT(s.median_segment_ms, 0.0);
  const std::string report = scenes_markdown(*r);
  EXPECT_NE(report.find("## Detection"), std::string::npos);
  EXPECT_NE(scenes_json(*r).find("\"recall\""), std::string::npos);
}

TEST(RunScenes, DoesNotDependOnTheThreadCount) {
  const std::vector<EvalObject> pool = zoo_objects(1, 99);
  ScenesParams one = small_run(), two = small_run();
  one.threads = 1, two.threads = 2;
  auto a = run_scenes(pool, nullptr, one), b = run_scenes(pool, nullptr, two);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->scenes.size(), b->scenes.size());
  for (size_t i = 0; i < a->scenes.size(); ++i) {
    EXPECT_EQ(a->scenes[i].frame_points, b->scenes[i].frame_points) << i;
    ASSERT_EQ(a->scenes[i].truth.size(), b->scenes[i].truth.size()) << i;
    for (size_t t = 0; t < a->scenes[i].truth.size(); ++t) {
      EXPECT_EQ(a->scenes[i].truth[t].points, b->scenes[i].truth[t].points);
      EXPECT_EQ(a->scenes[i].truth[t].detection, b->scenes[i].truth[t].detection);
      EXPECT_EQ(a->scenes[i].truth[t].miss, b->scenes[i].truth[t].miss);
    }
  }
}

// ---- detection on sources nothing was chosen on (docs/results.md#scenes) ----------------------------------

ScenesSummary detect_only(std::vector<EvalObject> pool, const char* name) {
  for (EvalObject& o : pool) o.role = EvalRole::kTestOnly;
  auto r = run_scenes(pool, nullptr, ScenesParams{});  // 50 scenes, seed 42, segment_scene's defaults
  EXPECT_TRUE(r.ok()) << r.error().message;
  if (!r.ok()) return {};
  const ScenesSummary s = summarise(*r);
  std::printf("%s scenes: recall %.1f %% (%zu / %zu), precision %.1f %% (%zu / %zu)\n", name, s.recall.percent(),
              s.recall.correct, s.recall.total, s.precision.percent(), s.precision.correct, s.precision.total);
  return s;
}

// `glimpse-lab scenes --detect-only --test-zoo 10`: the zoo made with seed 43.
TEST(SceneDetection, ZooScenesStayAboveTheirFloor) {
  std::vector<EvalObject> pool = zoo_objects(10, 43);
  for (EvalObject& o : pool) o.source = "zoo-test";
  const ScenesSummary s = detect_only(std::move(pool), "zoo");
  EXPECT_GE(s.recall.percent(), 77.0);     // measured 78.5
  EXPECT_GE(s.precision.percent(), 72.0);  // measured 73.4
}

// `glimpse-lab scenes --detect-only --test $D/psb`.
TEST(SceneDetection, PsbScenesStayAboveTheirFloor) {
  const char* env = std::getenv("GLIMPSE_PSB_DIR");
  const std::string dir = env ? env : GLIMPSE_SOURCE_DIR "/../shared/data/psb";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "PSB not found at " << dir << " (set GLIMPSE_PSB_DIR)";
  auto pool = load_dataset_objects(dir, 42, 0);
  ASSERT_TRUE(pool.ok()) << pool.error().message;
  const ScenesSummary s = detect_only(std::move(*pool), "PSB");
  EXPECT_GE(s.recall.percent(), 85.0);     // measured 86.5
  EXPECT_GE(s.precision.percent(), 83.0);  // measured 84.6
}

}  // namespace
}  // namespace glimpse
