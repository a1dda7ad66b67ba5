#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "glimpse/geometry/scene.h"
#include "glimpse/spatial_hash.h"

namespace glimpse {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Voxel labels: 0 = dropped, -(k + 1) = the k-th plane removed, c + 1 = the c-th cluster.
using Labels = std::vector<int32_t>;

std::unique_ptr<pcl::PointCloud<pcl::PointXYZ>> to_pcl(const Points& points) {
  auto cloud = std::make_unique<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->reserve(points.size());
  for (const Vec3& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return cloud;
}

struct Voxels {
  Points centroids;               // one per occupied voxel, in the order the frame first reaches them
  std::vector<uint32_t> of_point; // per frame point: its voxel, kNone when non-finite
  size_t finite = 0;
};

// The frame's finite points averaged per voxel, and each point's voxel (voxel_m 0: every finite point
// its own voxel). PCL's VoxelGrid averages the same way but says which voxel a point fell in only
// through its dense leaf layout (an int per cell of the frame's bounding grid: ~400 MB for a room at
// 1 cm), and each object takes back its voxels' points, so the grid is a hash of the cells here.
Voxels voxelise(const Points& frame, float voxel_m) {
  Voxels v;
  v.of_point.assign(frame.size(), kNone);
  std::unordered_map<CellKey, uint32_t, CellKeyHash> index;
  index.reserve(voxel_m > 0 ? frame.size() : 0);
  std::vector<Eigen::Vector3d> sums;
  std::vector<uint32_t> counts;
  for (uint32_t i = 0; i < frame.size(); ++i) {
    if (!frame[i].allFinite()) continue;
    ++v.finite;
    const uint32_t voxel =
        voxel_m > 0 ? index.try_emplace(cell_key(frame[i], voxel_m), uint32_t(sums.size())).first->second : uint32_t(sums.size());
    if (voxel == sums.size()) sums.emplace_back(Eigen::Vector3d::Zero()), counts.push_back(0);
    sums[voxel] += frame[i].cast<double>();
    ++counts[voxel];
    v.of_point[i] = voxel;
  }
  v.centroids.reserve(sums.size());
  for (size_t k = 0; k < sums.size(); ++k) v.centroids.push_back((sums[k] / double(counts[k])).cast<float>());
  return v;
}

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

// The large planes, largest first (fit_plane: PCL's RANSAC with its fixed seed), each taking the
// remaining voxels within the inlier distance that lie in its broad regions; the rest of its inliers
// stay for clustering and leave only RANSAC's candidates, so that the next fit finds another plane.
// Stops at the first plane holding fewer than min_plane_fraction of all voxels, or after max_planes fits.
std::vector<Plane> remove_planes(const Points& voxels, const Vec3& sensor, const SceneParams& params, Labels& labels) {
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

// The unlabelled voxels split into clusters: two voxels are joined when they lie within join_distance of
// each other. A breadth-first growth over PCL's kd-tree, each voxel's neighbours searched within its own
// join distance (PCL's Euclidean and conditional clusterings search one radius for every point, the
// farthest point's, which costs the near ones, the most, several times over). Labelled 1, 2, ... from
// the lowest unlabelled voxel up; returns their count.
int32_t cluster_voxels(const Points& voxels, const Vec3& sensor, const SceneParams& params, Labels& labels) {
  auto indices = std::make_shared<pcl::Indices>();
  for (uint32_t i = 0; i < voxels.size(); ++i)
    if (labels[i] == 0) indices->push_back(int(i));
  if (indices->empty()) return 0;
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud(to_pcl(voxels).release());
  pcl::search::KdTree<pcl::PointXYZ> tree(true);  // sorted results: the same clusters whatever the build
  tree.setInputCloud(cloud, indices);
  int32_t clusters = 0;
  pcl::Indices found;
  std::vector<float> distances;
  std::vector<int> queue;
  for (int seed : *indices) {
    if (labels[size_t(seed)] != 0) continue;
    labels[size_t(seed)] = ++clusters;
    queue.assign(1, seed);
    for (size_t head = 0; head < queue.size(); ++head) {
      const Vec3& p = voxels[size_t(queue[head])];
      const float reach = std::max(params.cluster_tolerance_m, params.cluster_tolerance_per_m2 * (p - sensor).squaredNorm());
      tree.radiusSearch(cloud->points[size_t(queue[head])], reach, found, distances);
      for (int q : found)
        if (labels[size_t(q)] == 0) labels[size_t(q)] = clusters, queue.push_back(q);
    }
  }
  return clusters;
}

// A single view parts one object where a near part hides what joins it to the rest (an arm before a
// body, a chair's back behind its seat): pieces of one object stand over one another as seen from above
// and share their heights, where two objects side by side do not and a cup on a table stands above it.
// Clusters of at least kMinVoxels whose boxes overlap in height, and whose footprints (x-y boxes) overlap
// by at least kShare of the smaller one's, the larger's grown by kMargin, are joined (union-find, in
// label order); returns the count. Only for a frame that is +z up (it has a floor or a table top).
int32_t join_overlapping(const Points& voxels, int32_t clusters, Labels& labels) {
  constexpr size_t kMinVoxels = 5;
  constexpr float kMargin = 0.f, kShare = 0.3f;  // chosen on scenes of SHREC 2007 meshes (docs/results.md)
  std::vector<Bounds> box(size_t(clusters), Bounds{Vec3::Constant(INFINITY), Vec3::Constant(-INFINITY)});
  std::vector<size_t> count(size_t(clusters), 0);
  for (size_t i = 0; i < voxels.size(); ++i)
    if (labels[i] > 0) {
      Bounds& b = box[size_t(labels[i] - 1)];
      b.min = b.min.cwiseMin(voxels[i]), b.max = b.max.cwiseMax(voxels[i]);
      ++count[size_t(labels[i] - 1)];
    }
  std::vector<int32_t> root(static_cast<size_t>(clusters));
  for (int32_t c = 0; c < clusters; ++c) root[size_t(c)] = c;
  auto find = [&root](int32_t c) {
    while (root[size_t(c)] != c) c = root[size_t(c)] = root[size_t(root[size_t(c)])];
    return c;
  };
  auto area = [](const Bounds& b) { return std::max(0.f, b.max.x() - b.min.x()) * std::max(0.f, b.max.y() - b.min.y()); };
  for (int32_t a = 0; a < clusters; ++a)
    for (int32_t b = a + 1; b < clusters && count[size_t(a)] >= kMinVoxels; ++b) {
      const Bounds &p = box[size_t(a)], &q = box[size_t(b)];
      if (count[size_t(b)] < kMinVoxels || p.max.z() < q.min.z() || q.max.z() < p.min.z()) continue;
      const bool a_smaller = area(p) < area(q);
      const Bounds& small = a_smaller ? p : q;
      const Bounds grown{(a_smaller ? q : p).min - Vec3::Constant(kMargin), (a_smaller ? q : p).max + Vec3::Constant(kMargin)};
      const Bounds both{small.min.cwiseMax(grown.min), small.max.cwiseMin(grown.max)};
      if (area(both) >= kShare * area(small)) root[size_t(find(b))] = find(a);
    }
  std::vector<int32_t> renumbered(size_t(clusters), 0);
  int32_t joined = 0;
  for (int32_t c = 0; c < clusters; ++c)
    if (find(c) == c) renumbered[size_t(c)] = ++joined;
  for (int32_t& label : labels)
    if (label > 0) label = renumbered[size_t(find(label - 1))];
  return joined;
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
std::vector<bool> idle_tops(const Points& voxels, const std::vector<Plane>& planes, const Labels& labels,
                            const SceneParams& params) {
  std::vector<bool> idle(planes.size(), false);
  constexpr float kLevelCos = 0.94f;  // within 20 degrees of +z
  // At least 20 cm² of it within reach of the top (a cup's foot), counted in voxels.
  const size_t kMinResting = std::max<size_t>(3, size_t(0.002f / std::max(1e-4f, params.voxel_m * params.voxel_m)));
  std::optional<float> floor_height;  // of the lowest level plane
  for (const Plane& p : planes)
    if (p.normal.z() >= kLevelCos && (!floor_height || -p.offset / p.normal.z() < *floor_height))
      floor_height = -p.offset / p.normal.z();
  const float cell_m = std::max(2.f * params.voxel_m, params.cluster_tolerance_m);
  const float reach_m = params.plane_distance_m + params.cluster_tolerance_m;
  for (size_t k = 0; k < planes.size(); ++k) {
    const Plane& plane = planes[k];
    if (plane.normal.z() < kLevelCos || -plane.offset / plane.normal.z() <= *floor_height + params.plane_distance_m)
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

// The planes kept and their voxels' labels renumbered; the idle ones' voxels unlabelled (0).
std::vector<Plane> restore_planes(std::vector<Plane> planes, const std::vector<bool>& idle, Labels& labels) {
  std::vector<int32_t> renumbered(planes.size(), 0);
  std::vector<Plane> kept;
  for (size_t k = 0; k < planes.size(); ++k)
    if (!idle[k]) renumbered[k] = -int32_t(kept.size() + 1), kept.push_back(planes[k]);
  for (int32_t& label : labels)
    if (label < 0) label = renumbered[size_t(-label - 1)];
  return kept;
}

SceneObject make_object(const Points& frame, std::vector<uint32_t> indices, const Vec3& sensor) {
  SceneObject o;
  o.indices = std::move(indices);
  o.points.reserve(o.indices.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (uint32_t i : o.indices) {
    o.points.push_back(frame[i]);
    sum += frame[i].cast<double>();
  }
  const Bounds box = bounds(o.points);
  o.box_min = box.min;
  o.box_max = box.max;
  o.centroid = (sum / double(std::max<size_t>(1, o.indices.size()))).cast<float>();
  o.range_m = (o.centroid - sensor).norm();
  return o;
}

// Whether the object is a removed plane's remnant: most of its points within twice the plane's reach.
bool remnant(const SceneObject& o, const std::vector<Plane>& planes, const Vec3& sensor, const SceneParams& params) {
  if (planes.empty()) return false;
  size_t near = 0;
  for (const Vec3& p : o.points) {
    const float reach = 2.f * plane_reach(p, sensor, params);
    near += std::any_of(planes.begin(), planes.end(),
                        [&](const Plane& plane) { return std::abs(plane.normal.dot(p) + plane.offset) <= reach; });
  }
  return double(near) >= params.max_remnant_share * double(o.points.size());
}

bool keep(const SceneObject& o, const std::vector<Plane>& planes, const Vec3& sensor, const SceneParams& params) {
  const size_t n = o.indices.size();
  return n >= params.min_object_points && n <= params.max_object_points &&
         (o.box_max - o.box_min).maxCoeff() <= params.max_object_extent_m && !remnant(o, planes, sensor, params);
}

Status check(const SceneParams& p) {
  if (!(p.voxel_m >= 0.f) || !std::isfinite(p.voxel_m)) return invalid_argument("scene: voxel_m must be 0 or more");
  if (!(p.plane_distance_m > 0.f)) return invalid_argument("scene: plane_distance_m must be positive");
  if (!(p.cluster_tolerance_m > 0.f)) return invalid_argument("scene: cluster_tolerance_m must be positive");
  if (p.min_object_points > p.max_object_points)
    return invalid_argument("scene: min_object_points " + std::to_string(p.min_object_points) + " is above max_object_points " +
                            std::to_string(p.max_object_points));
  return {};
}

}  // namespace

Expected<Scene> segment_scene(const Cloud& frame, const SceneParams& params) {
  if (Status s = check(params); !s) return s.error();
  const Voxels voxels = voxelise(frame.points, params.voxel_m);
  Scene scene;
  scene.finite_points = voxels.finite;
  Labels labels(voxels.centroids.size(), 0);
  const Vec3 sensor = frame.sensor.value_or(Vec3::Zero());
  scene.planes = remove_planes(voxels.centroids, sensor, params, labels);
  const std::vector<bool> idle = idle_tops(voxels.centroids, scene.planes, labels, params);
  if (std::find(idle.begin(), idle.end(), true) != idle.end())
    scene.planes = restore_planes(std::move(scene.planes), idle, labels);
  int32_t clusters = cluster_voxels(voxels.centroids, sensor, params, labels);
  if (has_level_plane(scene)) clusters = join_overlapping(voxels.centroids, clusters, labels);  // +z is up
  // Each frame point follows its voxel, in the frame's order: planes count points, clusters gather them.
  for (Plane& plane : scene.planes) plane.inliers = 0;
  std::vector<std::vector<uint32_t>> members(static_cast<size_t>(clusters));
  for (uint32_t i = 0; i < frame.points.size(); ++i) {
    if (voxels.of_point[i] == kNone) continue;
    const int32_t label = labels[voxels.of_point[i]];
    if (label < 0) ++scene.planes[size_t(-label - 1)].inliers;
    if (label > 0) members[size_t(label - 1)].push_back(i);
  }
  for (std::vector<uint32_t>& indices : members) {
    if (indices.size() < params.min_object_points || indices.size() > params.max_object_points) continue;
    SceneObject object = make_object(frame.points, std::move(indices), sensor);
    if (keep(object, scene.planes, sensor, params)) scene.objects.push_back(std::move(object));
  }
  std::sort(scene.objects.begin(), scene.objects.end(), [](const SceneObject& a, const SceneObject& b) {
    if (a.range_m != b.range_m) return a.range_m < b.range_m;
    if (a.indices.size() != b.indices.size()) return a.indices.size() > b.indices.size();
    return a.indices.front() < b.indices.front();
  });
  if (scene.objects.size() > params.max_objects) scene.objects.resize(params.max_objects);
  return scene;
}

}  // namespace glimpse
