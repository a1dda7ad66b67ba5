// Synthetic scenes for the scene segmentation (geometry/scene.h) and the recogniser behind it: 2-6 objects
// of a test source on a floor in front of a wall, some touching or hiding one another, seen by the
// simulated depth camera (views/sensors.h). Each frame point is labelled with the object it belongs to, so
// segment_scene's objects can be matched to the true ones by box overlap, and each matched object is
// classified as the scene gives it and as the same camera sees it alone. scene_render.cpp makes and
// labels the scenes, scenes.cpp scores them, scene_model.cpp trains the model, report_scenes.cpp writes
// the report.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/scene.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/learning/metrics.h"
#include "glimpse/learning/model.h"
#include "glimpse/views/sensors.h"

namespace glimpse {

// ---- Making a scene ------------------------------------------------------------------------------------

struct SceneLayout {
  size_t min_objects = 2, max_objects = 6;
  double touching_chance = 0.35;    // an object after the first stands 0-max_touch_gap_m from one before it
  double behind_chance = 0.3;       // ... or behind one, as the camera sees them, partly hidden
  float max_touch_gap_m = 0.02f;    // between the axis-aligned boxes of touching objects
  float min_behind_gap_m = 0.05f, max_behind_gap_m = 0.5f;
  float free_gap_m = 0.3f;          // a free-standing object's box this far from every other
  float spread_m = 1.0f;            // free-standing objects stand within this of the first one
  float min_distance_m = 1.5f, max_distance_m = 3.5f;  // the camera from the group's centre
  float min_down_deg = 10.f, max_down_deg = 40.f;      // the camera's elevation above the group
  float max_azimuth_deg = 30.f;     // the camera's azimuth off facing the wall squarely
  float wall_gap_m = 0.4f;          // the wall stands this far behind the farthest object
  float room_half_m = 4.f;          // the floor and the wall reach this far either side of the group
  float wall_height_m = 2.5f;
  DepthCameraParams camera;         // Kinect-class: 640 x 480, 57 x 43 deg
};

enum class Arrangement : uint8_t { kFree, kTouching, kBehind };

struct PlacedObject {
  size_t pool_index = 0;  // the object of the pool it shows
  Mesh mesh;              // in the room's coordinates (metres, +z up, on the floor z = 0)
  Bounds box;             // the mesh's axis-aligned box
  Arrangement arrangement = Arrangement::kFree;
  int anchor = -1;        // the object it touches or stands behind
};

struct RoomScene {
  uint64_t seed = 0;
  std::vector<PlacedObject> objects;
  Mesh room;              // the floor and the wall, as triangles
  Mesh floor;             // the floor alone
  SensorPose pose;
  Cloud frame;            // the depth camera's frame of objects and room
};

// Objects of `pool` (upright, real-life size, on the ground: EvalObject::mesh) placed on a floor in front
// of a wall and seen by layout.camera; an object without a natural up lies in a random pose. Seeded. An
// empty pool or a layout asking for no object is an error.
Expected<RoomScene> make_room_scene(const std::vector<EvalObject>& pool, const SceneLayout& layout, uint64_t seed);

// Per point of `frame`: the index into `objects` of the object whose surface its ray (from frame.sensor
// through the point) reaches first, when that is nearer than anything of `room`; -1 otherwise.
std::vector<int> label_points(const Cloud& frame, const std::vector<const RayScene*>& objects, const RayScene& room);

// The Euclidean distance between two axis-aligned boxes (0 when they overlap or touch).
float box_gap(const Bounds& a, const Bounds& b);

// ---- The truth of a scene --------------------------------------------------------------------------------

enum class SceneKind : uint8_t { kFree, kTouching, kOccluded };
const char* scene_kind_name(SceneKind kind);

struct ObjectView {
  std::vector<uint32_t> indices;  // the frame points it owns
  Bounds box;                     // their axis-aligned box: the true box
  size_t alone_points = 0;        // its points when the camera sees it alone on the floor
  double visible = 0;             // indices / alone_points
  bool touching = false;          // its mesh's box within max_touch_gap_m of another's
  bool occluded = false;          // other objects hide at least 10 % of what the camera sees of it alone
  SceneKind kind = SceneKind::kFree;  // touching first, then occluded
  Cloud alone;                    // its points in the view of it alone, with the frame's sensor and frame
};

// Every object's labelled points, true box, visible share and kind (the frame labelled by label_points,
// each object seen alone on the floor from the same pose).
Expected<std::vector<ObjectView>> scene_truth(const RoomScene& scene, const SceneLayout& layout);

// ---- Matching detections to the truth ------------------------------------------------------------------

// Intersection over union of two axis-aligned boxes; identical boxes 1 (even flat ones), disjoint 0.
double box_iou(const Bounds& a, const Bounds& b);

struct BoxMatch {
  int detection = -1, truth = -1;
  double iou = 0;
};
// One-to-one, greedy by IoU (highest first; ties by detection, then truth index): every pair at least
// min_iou.
std::vector<BoxMatch> match_boxes(const std::vector<Bounds>& detections, const std::vector<Bounds>& truth,
                                  double min_iou);

// ---- Evaluating scenes ------------------------------------------------------------------------------------

struct ScenesParams {
  size_t scenes = 50;
  uint64_t seed = 42;
  SceneLayout layout;
  SceneParams segmentation;   // segment_scene's parameters under test
  double min_visible = 0.3;   // objects less visible are neither to be found nor wrong when found
  double min_iou = 0.5;
  int threads = 0;            // 0: all cores; results do not depend on it
};

struct Verdict {
  bool decided = false;  // classify answered
  std::string winner;    // the closest category
  bool unknown = false;  // "none of these" at the model's operating point
  size_t points = 0;
};

struct TruthOutcome {
  std::string category, id, source;  // of the pool object
  SceneKind kind = SceneKind::kFree;
  bool touching = false, occluded = false;
  double visible = 0;
  size_t points = 0;
  Vec3 extent = Vec3::Zero();  // of the true box
  float range_m = 0;           // its labelled points' centroid from the sensor
  int detection = -1;          // matched, else -1
  double iou = 0;
  std::string miss;            // why it was not matched (empty when matched or under min_visible)
  Verdict scene, alone;        // matched and at least min_visible, with a model
};

struct DetectionOutcome {
  Bounds box;
  size_t points = 0;
  float range_m = 0;           // SceneObject::range_m
  int truth = -1;              // matched, else -1
  std::string origin;          // unmatched: what its points are ("room", "part of chair", ...)
};

struct SceneOutcome {
  uint64_t seed = 0;
  SensorPose pose;
  size_t frame_points = 0, planes = 0;
  double segment_ms = 0;
  std::vector<TruthOutcome> truth;
  std::vector<DetectionOutcome> detections;
};

struct ScenesResult {
  ScenesParams params;
  std::string trained_on, tested_on, tuned_on;  // what the model learnt, the pool, where params were chosen
  std::vector<std::string> categories;          // the model's
  std::vector<SceneOutcome> scenes;
  std::vector<PhaseTiming> timings;
  double total_seconds = 0;
  int threads = 1;
};

// A segmented scene's detections matched to its truth (`room`'s objects are of `pool`), with why each true
// object at least min_visible went unfound and what each unmatched detection holds; not classified.
SceneOutcome score_scene(const RoomScene& room, const std::vector<ObjectView>& truth, const Scene& segmented,
                         const std::vector<EvalObject>& pool, const ScenesParams& params);

// `scenes` scenes of `pool`, segmented, matched and (with a model) classified; segment_scene is timed on
// one frame at a time.
Expected<ScenesResult> run_scenes(const std::vector<EvalObject>& pool, const Model* model, const ScenesParams& params,
                                  const EvalProgressFn& progress = {});

// The figures of a run: detection over objects at least min_visible, by kind, and classification.
struct ScenesSummary {
  Tally recall, precision;
  std::array<Tally, 3> recall_by_kind;  // SceneKind order
  size_t ignored_detections = 0;        // matched to objects less visible than min_visible
  Tally scene_closest, scene_accepted, alone_closest, alone_accepted;  // the same objects
  size_t scene_unknown = 0, alone_unknown = 0;
  double median_segment_ms = 0, max_segment_ms = 0;
  size_t objects = 0, visible_objects = 0, detections = 0;
};
ScenesSummary summarise(const ScenesResult& result);

// ---- Training and the report -------------------------------------------------------------------------------

// The model the lab learns of `objects` (those of role kTrainOnly or kCrossValidate): each object's views
// as glimpse-lab eval makes them (the ideal views, the training sensors' thinned to the ideal views' median
// density), learnt by core's train() with params.train, params.methods, seed and threads. The zoo beside
// other sources and the sensors' views are augmented, as in eval.
Expected<Model> train_lab_model(const std::vector<EvalObject>& objects, const EvalParams& params,
                                const EvalProgressFn& progress = {});

std::string scenes_markdown(const ScenesResult& result);
std::string scenes_json(const ScenesResult& result);
// One row per true object of every scene.
std::string scene_objects_csv(const ScenesResult& result);
// report.md, scenes.json and objects.csv in `dir` (created).
Status write_scenes_report(const ScenesResult& result, const std::string& dir);

}  // namespace glimpse
