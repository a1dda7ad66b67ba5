#include "glimpse/session/scene_tracking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

namespace glimpse {
namespace {

// An object chosen in a frame, or why none was.
struct Pick {
  std::optional<size_t> index;
  std::string why;
};

bool inside(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

// The distance from `p` to the box [lo, hi]; 0 inside.
float box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(0.f).norm();
}

// The object whose centroid lies nearest the optical axis in angle; without a camera frame, the nearest
// the sensor (the scene lists objects nearest first).
Pick nearest_axis(const Cloud& frame, const std::vector<SceneObject>& objects) {
  if (!frame.frame) return {0, {}};
  const Vec3 sensor = frame.sensor.value_or(Vec3::Zero()), axis = frame.frame->axis.normalized();
  size_t best = 0;
  float best_cos = -2.f;
  for (size_t k = 0; k < objects.size(); ++k) {
    const float c = (objects[k].centroid - sensor).normalized().dot(axis);
    if (c > best_cos) best = k, best_cos = c;
  }
  return {best, {}};
}

// The object whose box holds `point` (of several, the one whose centroid is nearest it), else the one
// whose box is nearest it, within radius_m.
Pick at_point(const Vec3& point, const std::vector<SceneObject>& objects, float radius_m) {
  std::optional<size_t> best;
  std::pair<bool, float> best_key;
  for (size_t k = 0; k < objects.size(); ++k) {
    const float d = box_distance(point, objects[k].box_min, objects[k].box_max);
    // Boxes that hold the point rank first, among them by centroid distance.
    const std::pair<bool, float> key{d > 0, d > 0 ? d : (objects[k].centroid - point).norm()};
    if (d <= radius_m && (!best || key < best_key)) best = k, best_key = key;
  }
  if (best) return {best, {}};
  char why[96];
  std::snprintf(why, sizeof why, "no object within %.2f m of the point", double(radius_m));
  return {std::nullopt, why};
}

// The object with the most points inside the box [lo, hi].
Pick in_box(const Vec3& lo, const Vec3& hi, const std::vector<SceneObject>& objects) {
  std::optional<size_t> best;
  size_t best_count = 0;
  for (size_t k = 0; k < objects.size(); ++k) {
    const auto n = size_t(std::count_if(objects[k].points.begin(), objects[k].points.end(),
                                        [&](const Vec3& p) { return inside(p, lo, hi); }));
    if (n > best_count) best = k, best_count = n;
  }
  if (best) return {best, {}};
  return {std::nullopt, "no object has points inside the box"};
}

// The centroids of an object's points per cell of cell_m.
Points cell_centroids(const Points& points, float cell_m) {
  std::unordered_map<CellKey, uint32_t, CellKeyHash> index;
  std::vector<Eigen::Vector3d> sums;
  std::vector<uint32_t> counts;
  for (const Vec3& p : points) {
    const uint32_t c = index.try_emplace(cell_key(p, cell_m), uint32_t(sums.size())).first->second;
    if (c == sums.size()) sums.emplace_back(Eigen::Vector3d::Zero()), counts.push_back(0);
    sums[c] += p.cast<double>();
    ++counts[c];
  }
  Points out;
  out.reserve(sums.size());
  for (size_t c = 0; c < sums.size(); ++c) out.push_back((sums[c] / double(counts[c])).cast<float>());
  return out;
}

// Whether `p` lies inside the image of the frame's camera; nullopt without a sensor and a camera frame.
std::optional<bool> in_view(const Cloud& frame, const Vec3& p) {
  if (!frame.sensor || !frame.frame) return std::nullopt;
  const CameraFrame& c = *frame.frame;
  if (!(c.fov_h_deg > 0 && c.fov_h_deg < 180 && c.fov_v_deg > 0 && c.fov_v_deg < 180)) return std::nullopt;
  const Vec3 d = p - *frame.sensor, right = c.axis.cross(c.up);
  const float depth = d.dot(c.axis), half = std::numbers::pi_v<float> / 360.f;  // degrees to half-angle radians
  return depth > 0 && std::abs(d.dot(right)) <= depth * std::tan(c.fov_h_deg * half) &&
         std::abs(d.dot(c.up)) <= depth * std::tan(c.fov_v_deg * half);
}

// Why a target once found is not in `frame`.
std::string lost_reason(const Cloud& frame, const Bounds& seen) {
  const std::optional<bool> visible = in_view(frame, seen.centre());
  if (visible && !*visible) return "the target left the view: its seen box lies outside the image";
  const std::string why = "no object shares its seen surface or stands inside its seen box";
  return visible ? "the target is hidden or gone: in view, but " + why : "the target is out of view or hidden: " + why;
}

// The object the target names, before it was ever found.
Pick first_find(const TrackTarget& target, float point_radius_m, const Cloud& frame, const std::vector<SceneObject>& objects) {
  switch (target.kind) {
    case TrackTarget::Kind::kNearestAxis: return nearest_axis(frame, objects);
    case TrackTarget::Kind::kPoint: return at_point(target.point, objects, point_radius_m);
    case TrackTarget::Kind::kBox: return in_box(target.box_min, target.box_max, objects);
  }
  return {std::nullopt, "unknown target kind"};
}

}  // namespace

Expected<SceneTracker> SceneTracker::create(const TrackTarget& target, const TrackParams& params) {
  using Kind = TrackTarget::Kind;
  if (target.kind != Kind::kNearestAxis && target.kind != Kind::kPoint && target.kind != Kind::kBox)
    return invalid_argument("track: unknown target kind " + std::to_string(int(target.kind)));
  if (!target.point.allFinite()) return invalid_argument("track: the target point must be finite");
  if (!target.box_min.allFinite() || !target.box_max.allFinite()) return invalid_argument("track: the target box must be finite");
  if ((target.box_min.array() > target.box_max.array()).any())
    return invalid_argument("track: the target box's min is above its max");
  if (!(params.point_radius_m >= 0.f) || !std::isfinite(params.point_radius_m))
    return invalid_argument("track: point_radius_m must be 0 or more");
  if (!(params.match_distance_m > 0.f) || !std::isfinite(params.match_distance_m))
    return invalid_argument("track: match_distance_m must be positive");
  if (!(params.fuse_cell_m > 0.f) || !std::isfinite(params.fuse_cell_m))
    return invalid_argument("track: fuse_cell_m must be positive");
  if (!(params.min_shared_fraction >= 0.0 && params.min_shared_fraction <= 1.0))
    return invalid_argument("track: min_shared_fraction must lie in [0, 1]");
  if (Expected<Scene> empty = segment_scene(Cloud{}, params.scene); !empty) return empty.error();  // checks the scene params
  return SceneTracker(target, params);
}

Expected<TrackStep> SceneTracker::next(const Cloud& frame) {
  Expected<Scene> scene = segment_scene(frame, params_.scene);
  if (!scene) return scene.error();
  TrackStep step;
  step.objects = scene->objects.size();
  if (scene->objects.empty()) {
    step.not_found = "no objects in the frame";
    return step;
  }
  const Pick pick = acquired_ ? Pick{follow(scene->objects), lost_reason(frame, seen_box_)}
                              : first_find(target_, params_.point_radius_m, frame, scene->objects);
  if (!pick.index) {
    step.not_found = pick.why;
    return step;
  }
  step.found = true;
  step.object = std::move(scene->objects[*pick.index]);
  step.fresh = remember(step.object);
  return step;
}

// The object with the most cells on the seen surface, when enough of its cells are; else the one whose
// centroid lies inside the seen surface's box (the nearest the box's centre of several).
std::optional<size_t> SceneTracker::follow(const std::vector<SceneObject>& objects) const {
  std::optional<size_t> best;
  size_t best_shared = 0;
  for (size_t k = 0; k < objects.size(); ++k) {
    const Points cells = cell_centroids(objects[k].points, params_.match_distance_m);
    const size_t shared = shared_cells(cells);
    const bool enough = shared >= std::max<size_t>(1, params_.min_shared_cells) &&
                        double(shared) >= params_.min_shared_fraction * double(cells.size());
    if (enough && shared > best_shared) best = k, best_shared = shared;
  }
  if (best) return best;
  const Vec3 grow = Vec3::Constant(params_.match_distance_m);
  float best_distance = std::numeric_limits<float>::infinity();
  for (size_t k = 0; k < objects.size(); ++k) {
    if (!inside(objects[k].centroid, seen_box_.min - grow, seen_box_.max + grow)) continue;
    const float d = (objects[k].centroid - seen_box_.centre()).norm();
    if (d < best_distance) best = k, best_distance = d;
  }
  return best;
}

// How many of the cells' centroids lie within match_distance_m of a seen cell's centroid.
size_t SceneTracker::shared_cells(const Points& cell_centroids) const {
  const float cell = params_.match_distance_m;
  const double reach2 = double(cell) * double(cell);
  size_t shared = 0;
  for (const Vec3& c : cell_centroids) {
    const CellKey key = cell_key(c, cell);
    const Eigen::Vector3d centroid = c.cast<double>();
    bool near = false;
    for (int64_t dx = -1; dx <= 1 && !near; ++dx)
      for (int64_t dy = -1; dy <= 1 && !near; ++dy)
        for (int64_t dz = -1; dz <= 1 && !near; ++dz) {
          const auto it = seen_.find({key.x + dx, key.y + dy, key.z + dz});
          near = it != seen_.end() && (it->second.sum / double(it->second.count) - centroid).squaredNorm() <= reach2;
        }
    shared += near;
  }
  return shared;
}

// Adds the object's points to the seen surface and its box to the seen box.
Points SceneTracker::remember(const SceneObject& object) {
  if (!acquired_) {
    seen_box_ = {object.box_min, object.box_max};
    acquired_ = true;
  } else {
    seen_box_.min = seen_box_.min.cwiseMin(object.box_min);
    seen_box_.max = seen_box_.max.cwiseMax(object.box_max);
  }
  for (const Vec3& p : object.points) {
    CellSum& cell = seen_[cell_key(p, params_.match_distance_m)];
    cell.sum += p.cast<double>();
    ++cell.count;
  }
  // A cell's points of this frame all count as fresh when the cell is new: the first frame gives its
  // cluster whole, later ones what they add.
  std::vector<CellKey> added;
  Points fresh;
  for (const Vec3& p : object.points) {
    const CellKey key = cell_key(p, params_.fuse_cell_m);
    if (fused_.count(key)) continue;
    fresh.push_back(p);
    added.push_back(key);
  }
  fused_.insert(added.begin(), added.end());
  return fresh;
}

}  // namespace glimpse
