// One object followed through a stream of scene frames: the sensor moves between frames, the objects
// stand still, and every frame arrives in the stream's common frame (world, metres). The first frames
// look for the object by the rule the stream names (TrackTarget); once found, each frame takes the
// object that shares surface with what has been seen of the target so far.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/scene.h"
#include "glimpse/spatial_hash.h"

namespace glimpse {

// The object to follow, as the stream's first chunk names it.
struct TrackTarget {
  enum class Kind {
    kNearestAxis,  // the object nearest the camera's optical axis (without a camera frame: nearest the sensor)
    kPoint,        // the object whose box holds `point`, else the nearest within TrackParams::point_radius_m
    kBox,          // the object with the most points inside [box_min, box_max]
  };
  Kind kind = Kind::kNearestAxis;
  Vec3 point = Vec3::Zero();
  Vec3 box_min = Vec3::Zero(), box_max = Vec3::Zero();
};

struct TrackParams {
  SceneParams scene;
  // kPoint: an object whose box is at most this far from the point, when no box holds it.
  float point_radius_m = 0.3f;
  // Following compares surfaces cell by cell, in cells this wide: a cell of a frame's object is on the
  // seen surface when the centroid of a seen cell lies this close to its own centroid. Above the sensor's
  // noise and the drift of its pose, below the gap that parts two objects (scene.cluster_tolerance_m).
  float match_distance_m = 0.02f;
  // The object taken as the target has at least this many cells (and at least 1) on the seen surface ...
  size_t min_shared_cells = 5;
  // ... and this share of its cells: a neighbour that touches the target shares a rim at most. When no
  // object qualifies, the object whose centroid lies inside the seen surface's box (grown by
  // match_distance_m) is taken: the target seen again from a side that shares nothing with the seen one.
  double min_shared_fraction = 0.2;
  // TrackStep::fresh keeps the points in cells of this size that no earlier found cluster reached.
  float fuse_cell_m = 0.01f;
};

struct TrackStep {
  bool found = false;
  SceneObject object;     // the target's cluster in this frame, when found
  // Its points that add to what earlier frames gave of it: those in a cell of TrackParams::fuse_cell_m
  // no earlier found cluster reached. A still camera's frames repeat one surface with new noise; fusing
  // only these keeps the scan as large as the surface, not as the stream is long.
  Points fresh;
  size_t objects = 0;     // objects segmented in this frame
  std::string not_found;  // why not, when not found
};

class SceneTracker {
 public:
  // Errors (kInvalidArgument): an unknown kind, a non-finite point or box, box_min above box_max, bad params.
  static Expected<SceneTracker> create(const TrackTarget& target, const TrackParams& params = {});

  // Segments `frame` and finds the target's cluster in it; a found cluster joins what has been seen of
  // the target. A frame without the target (out of view, hidden, no objects at all) is a step with
  // found = false that leaves the memory as it is; errors are segment_scene's. Deterministic: the same
  // frames give the same steps.
  Expected<TrackStep> next(const Cloud& frame);

  bool acquired() const { return acquired_; }       // found in some frame so far
  Bounds seen_bounds() const { return seen_box_; }  // the union box of its clusters so far

 private:
  SceneTracker(const TrackTarget& target, const TrackParams& params) : target_(target), params_(params) {}
  std::optional<size_t> follow(const std::vector<SceneObject>& objects) const;
  size_t shared_cells(const Points& cell_centroids) const;
  // Adds the object to the seen surface and box; returns its points in cells not fused before.
  Points remember(const SceneObject& object);

  struct CellSum {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t count = 0;
  };
  TrackTarget target_;
  TrackParams params_;
  // The seen surface: the target's points of every frame it was found in, summed per cell of
  // match_distance_m; it grows no larger than the target's surface.
  std::unordered_map<CellKey, CellSum, CellKeyHash> seen_;
  Bounds seen_box_;  // the union of its clusters' boxes
  std::unordered_set<CellKey, CellKeyHash> fused_;  // cells of fuse_cell_m that found clusters reached
  bool acquired_ = false;
};

}  // namespace glimpse
