// segment_scene's plane steps: RANSAC's large planes in their broad regions, and which of them bound the
// room or hold objects (scene_steps.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/Geometry>

#include "glimpse/spatial_hash.h"
#include "scene_steps.h"

namespace glimpse {
namespace {

// Every step-th of `subset`, at most `max_points`: RANSAC's cost grows with the points it scores, a
// plane's coefficients hardly with them.
std::vector<uint32_t> even_subsample(const std::vector<uint32_t>& subset, size_t max_points) {
  const size_t step = std::max<size_t>(1, (subset.size() + max_points - 1) / std::max<size_t>(1, max_points));
  std::vector<uint32_t> out;
  out.reserve(subset.size() / step + 1);
  for (size_t k = 0; k < subset.size(); k += step) out.push_back(subset[k]);
  return out;
}

// The inliers of a plane that lie in its broad connected regions: the inliers projected onto a grid of
// cell_m cells in the plane, the occupied cells joined to their 8 neighbours, and a region kept when its
// cells cover at least min_area_m2. A floor, wall or table top is one broad region; an object's face (a
// box's top, a screen) or a slice of an object that happens to lie in the plane is a small one.
std::vector<uint32_t> broad_regions(const Points& voxels, const std::vector<uint32_t>& inliers, const Vec3& normal,
                                    float cell_m, float min_area_m2) {
  const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
  std::vector<CellKey> key_of(inliers.size());  // the cell in the plane's (u, v) coordinates, z 0
  std::unordered_map<CellKey, int32_t, CellKeyHash> region_of;  // -1: not yet reached
  for (size_t k = 0; k < inliers.size(); ++k) {
    const Vec3& p = voxels[inliers[k]];
    key_of[k] = {grid_cell<int64_t>(u.dot(p), cell_m), grid_cell<int64_t>(v.dot(p), cell_m), 0};
    region_of.emplace(key_of[k], -1);
  }
  std::vector<size_t> cells_in;  // per region
  std::vector<CellKey> stack;
  for (size_t k = 0; k < inliers.size(); ++k) {  // flood fill from each unreached cell, in the inliers' order
    if (region_of[key_of[k]] >= 0) continue;
    const int32_t region = int32_t(cells_in.size());
    cells_in.push_back(0);
    region_of[key_of[k]] = region;
    stack.assign(1, key_of[k]);
    while (!stack.empty()) {
      const CellKey key = stack.back();
      stack.pop_back();
      ++cells_in.back();
      for (int64_t da = -1; da <= 1; ++da)
        for (int64_t db = -1; db <= 1; ++db) {
          const auto it = region_of.find(CellKey{key.x + da, key.y + db, 0});
          if (it == region_of.end() || it->second >= 0) continue;
          it->second = region;
          stack.push_back(it->first);
        }
    }
  }
  std::vector<uint32_t> broad;
  for (size_t k = 0; k < inliers.size(); ++k)
    if (float(cells_in[size_t(region_of[key_of[k]])]) * cell_m * cell_m >= min_area_m2) broad.push_back(inliers[k]);
  return broad;
}

// Whether voxel p lies on the top of the k-th plane: above it (on the sensor's side, which is up for a
// level plane below the sensor) by at most reach_m, over a cell of its footprint or next to one.
bool rests_on(const Vec3& p, const Plane& plane, const std::unordered_set<CellKey, CellKeyHash>& footprint,
              float cell_m, float reach_m) {
  const float above = plane.normal.dot(p) + plane.offset;
  if (above <= 0 || above > reach_m) return false;
  const int64_t x = grid_cell<int64_t>(p.x(), cell_m), y = grid_cell<int64_t>(p.y(), cell_m);
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      if (footprint.count(CellKey{x + dx, y + dy, 0})) return true;
  return false;
}

// The level planes above the lowest one (table tops, not the floor) on which nothing rests (fewer than
// kMinResting of the voxels left for clustering: a stray return or two): such a plane is an object's own
// face (a bare table's top, a low cabinet's), so its voxels go back to clustering. A frame that is not
// +z up has no level plane and keeps every plane.
std::vector<bool> idle_tops(const Points& voxels, const std::vector<Plane>& planes, const SceneLabels& labels,
                            const SceneParams& params) {
  std::vector<bool> idle(planes.size(), false);
  // At least 20 cm² of it within reach of the top (a cup's foot), counted in voxels.
  const size_t kMinResting = std::max<size_t>(3, size_t(0.002f / std::max(1e-4f, params.voxel_m * params.voxel_m)));
  const std::optional<float> floor = floor_height(planes);
  const float cell_m = std::max(2.f * params.voxel_m, params.cluster_tolerance_m);
  const float reach_m = params.plane_distance_m + params.cluster_tolerance_m;
  for (size_t k = 0; k < planes.size(); ++k) {
    const Plane& plane = planes[k];
    if (!is_level(plane) || level_height(plane) <= *floor + params.plane_distance_m)
      continue;
    std::unordered_set<CellKey, CellKeyHash> footprint;
    for (size_t i = 0; i < voxels.size(); ++i)
      if (labels[i] == -int32_t(k + 1))
        footprint.insert({grid_cell<int64_t>(voxels[i].x(), cell_m), grid_cell<int64_t>(voxels[i].y(), cell_m), 0});
    size_t resting = 0;
    for (size_t i = 0; i < voxels.size() && resting < kMinResting; ++i)
      resting += labels[i] == 0 && rests_on(voxels[i], plane, footprint, cell_m, reach_m);
    idle[k] = resting < kMinResting;
  }
  return idle;
}

// The planes that are not level and are no wall: some of the frame lies behind them. A wall, like the
// floor, ends the room: nothing is seen beyond it. An object's broad face (a person facing the camera, an
// animal's flank, a cabinet's door) has the room behind it: the floor and the wall beyond, the rest of
// the object. Behind: on the side away from the sensor by more than twice the plane's reach, over a cell
// of the plane's own voxels (cells in the plane, cell_m wide); more than kMaxBehindShare of the plane's
// voxels (a stray return or two behind a wall is noise). Marked in `face`.
void object_faces(const Points& voxels, const std::vector<Plane>& planes, const SceneLabels& labels, const Vec3& sensor,
                  const SceneParams& params, std::vector<bool>& face) {
  constexpr double kMaxBehindShare = 0.005;  // chosen on scenes of SHREC 2007 meshes (docs/results.md)
  const float cell_m = std::max(2.f * params.voxel_m, params.cluster_tolerance_m);
  for (size_t k = 0; k < planes.size(); ++k) {
    const Plane& plane = planes[k];
    if (is_level(plane)) continue;
    const Vec3 u = plane.normal.unitOrthogonal(), v = plane.normal.cross(u);
    auto cell = [&](const Vec3& p) {
      return CellKey{grid_cell<int64_t>(u.dot(p), cell_m), grid_cell<int64_t>(v.dot(p), cell_m), 0};
    };
    const int32_t own_label = -int32_t(k + 1);
    std::unordered_set<CellKey, CellKeyHash> footprint;
    size_t own = 0;
    for (size_t i = 0; i < voxels.size(); ++i)
      if (labels[i] == own_label) footprint.insert(cell(voxels[i])), ++own;
    const size_t most = size_t(kMaxBehindShare * double(own));
    size_t behind = 0;
    for (size_t i = 0; i < voxels.size() && behind <= most; ++i)
      behind += labels[i] != own_label &&
                plane.normal.dot(voxels[i]) + plane.offset < -2.f * plane_reach(voxels[i], sensor, params) &&
                footprint.count(cell(voxels[i]));
    face[k] = behind > most;
  }
}

// The planes kept and their voxels' labels renumbered; the idle ones' voxels unlabelled (0).
std::vector<Plane> restore_planes(std::vector<Plane> planes, const std::vector<bool>& idle, SceneLabels& labels) {
  std::vector<int32_t> renumbered(planes.size(), 0);
  std::vector<Plane> kept;
  for (size_t k = 0; k < planes.size(); ++k)
    if (!idle[k]) renumbered[k] = -int32_t(kept.size() + 1), kept.push_back(planes[k]);
  for (int32_t& label : labels)
    if (label < 0) label = renumbered[size_t(-label - 1)];
  return kept;
}

}  // namespace

std::optional<float> floor_height(const std::vector<Plane>& planes) {
  std::optional<float> lowest;
  for (const Plane& p : planes)
    if (is_level(p) && (!lowest || level_height(p) < *lowest)) lowest = level_height(p);
  return lowest;
}

// The large planes, largest first (fit_plane: PCL's RANSAC with its fixed seed), each taking the
// remaining voxels within the inlier distance that lie in its broad regions; the rest of its inliers
// stay for clustering and leave only RANSAC's candidates, so that the next fit finds another plane.
// Stops at the first plane holding fewer than min_plane_fraction of all voxels, or after max_planes fits.
std::vector<Plane> remove_planes(const Points& voxels, const Vec3& sensor, const SceneParams& params, SceneLabels& labels) {
  std::vector<uint32_t> remaining(voxels.size()), inliers, rest;
  for (uint32_t i = 0; i < remaining.size(); ++i) remaining[i] = i;
  const size_t min_inliers = std::max<size_t>(3, size_t(std::ceil(params.min_plane_fraction * double(voxels.size()))));
  const PlaneFitParams fit{params.plane_distance_m, 1000, std::nullopt, 90.f};
  const float cell_m = std::max(2.f * params.voxel_m, params.cluster_tolerance_m);
  std::vector<Plane> planes;
  for (int k = 0; k < params.max_planes && remaining.size() >= min_inliers; ++k) {
    const std::optional<Plane> plane = fit_plane(voxels, even_subsample(remaining, params.plane_fit_points), fit);
    if (!plane) break;
    inliers.clear();
    rest.clear();
    for (uint32_t i : remaining)
      (std::abs(plane->normal.dot(voxels[i]) + plane->offset) <= plane_reach(voxels[i], sensor, params) ? inliers : rest)
          .push_back(i);
    if (inliers.size() < min_inliers) break;
    remaining.swap(rest);
    const std::vector<uint32_t> broad = broad_regions(voxels, inliers, plane->normal, cell_m, params.min_plane_area_m2);
    if (broad.empty()) continue;
    for (uint32_t i : broad) labels[i] = -int32_t(planes.size() + 1);
    const float side = plane->normal.dot(sensor) + plane->offset < 0 ? -1.f : 1.f;  // the normal faces the sensor
    planes.push_back(Plane{side * plane->normal, side * plane->offset, broad.size()});
  }
  return planes;
}

std::vector<Plane> keep_room_and_supports(std::vector<Plane> planes, const Points& voxels, const Vec3& sensor,
                                          const SceneParams& params, SceneLabels& labels) {
  std::vector<bool> idle = idle_tops(voxels, planes, labels, params);
  if (floor_height(planes)) object_faces(voxels, planes, labels, sensor, params, idle);  // +z is up
  if (std::find(idle.begin(), idle.end(), true) == idle.end()) return planes;
  return restore_planes(std::move(planes), idle, labels);
}

}  // namespace glimpse
