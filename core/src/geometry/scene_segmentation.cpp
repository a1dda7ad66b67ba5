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
#include "scene_steps.h"

namespace glimpse {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

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

// The unlabelled voxels split into clusters: two voxels are joined when they lie within join_distance of
// each other. Each voxel's neighbours within its own join distance are searched over PCL's kd-tree, in
// parallel (PCL's Euclidean and conditional clusterings search one radius for every point, the farthest
// point's, which costs the near ones, the most, several times over); a breadth-first growth over them
// then labels the clusters 1, 2, ... from the lowest unlabelled voxel up. Returns their count.
int32_t cluster_voxels(const Points& voxels, const Vec3& sensor, const SceneParams& params, SceneLabels& labels) {
  auto indices = std::make_shared<pcl::Indices>();
  for (uint32_t i = 0; i < voxels.size(); ++i)
    if (labels[i] == 0) indices->push_back(int(i));
  if (indices->empty()) return 0;
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud(to_pcl(voxels).release());
  pcl::search::KdTree<pcl::PointXYZ> tree(false);  // unsorted: a cluster holds what it reaches, in any order
  tree.setInputCloud(cloud, indices);
  const ptrdiff_t n = ptrdiff_t(indices->size());
  std::vector<pcl::Indices> near(static_cast<size_t>(n));  // per unlabelled voxel, in indices' order
#pragma omp parallel
  {
    std::vector<float> distances;
#pragma omp for schedule(dynamic, 512)
    for (ptrdiff_t k = 0; k < n; ++k) {
      const int i = (*indices)[size_t(k)];
      const float reach = std::max(params.cluster_tolerance_m, params.cluster_tolerance_per_m2 * (voxels[size_t(i)] - sensor).squaredNorm());
      tree.radiusSearch(cloud->points[size_t(i)], reach, near[size_t(k)], distances);
    }
  }
  std::vector<int32_t> position(voxels.size(), -1);
  for (ptrdiff_t k = 0; k < n; ++k) position[size_t((*indices)[size_t(k)])] = int32_t(k);
  int32_t clusters = 0;
  std::vector<int> queue;
  for (int seed : *indices) {
    if (labels[size_t(seed)] != 0) continue;
    labels[size_t(seed)] = ++clusters;
    queue.assign(1, seed);
    for (size_t head = 0; head < queue.size(); ++head)
      for (int q : near[size_t(position[size_t(queue[head])])])
        if (labels[size_t(q)] == 0) labels[size_t(q)] = clusters, queue.push_back(q);
  }
  return clusters;
}

// A single view parts one object where a near part hides what joins it to the rest (an arm before a
// body, a chair's back behind its seat, an animal's far legs): pieces of one object stand over one
// another as seen from above, where two objects side by side do not and a cup on a table stands above
// the table's legs with the table top between them. Clusters of at least kMinVoxels whose footprints
// (x-y boxes) overlap by at least kShare of the smaller one's, whose heights overlap or leave at most
// kMaxGap between them, and with no removed level plane (a table top) in that gap, are joined
// (union-find, in label order); returns the count. Only for a frame that is +z up.
int32_t join_overlapping(const Points& voxels, int32_t clusters, const std::vector<Plane>& planes, SceneLabels& labels) {
  constexpr size_t kMinVoxels = 5;
  constexpr float kShare = 0.3f, kMaxGap = 0.6f;  // chosen on scenes of SHREC 2007 meshes (docs/results.md)
  std::vector<Bounds> box(size_t(clusters), Bounds{Vec3::Constant(INFINITY), Vec3::Constant(-INFINITY)});
  std::vector<size_t> count(size_t(clusters), 0);
  for (size_t i = 0; i < voxels.size(); ++i)
    if (labels[i] > 0) {
      Bounds& b = box[size_t(labels[i] - 1)];
      b.min = b.min.cwiseMin(voxels[i]), b.max = b.max.cwiseMax(voxels[i]);
      ++count[size_t(labels[i] - 1)];
    }
  ClusterJoins joins(clusters);
  auto area = [](const Bounds& b) { return std::max(0.f, b.max.x() - b.min.x()) * std::max(0.f, b.max.y() - b.min.y()); };
  auto support_between = [&planes](float below, float above) {  // a removed level plane in the gap
    return std::any_of(planes.begin(), planes.end(), [&](const Plane& plane) {
      return is_level(plane) && level_height(plane) >= below - 0.02f && level_height(plane) <= above + 0.02f;
    });
  };
  for (int32_t a = 0; a < clusters; ++a)
    for (int32_t b = a + 1; b < clusters && count[size_t(a)] >= kMinVoxels; ++b) {
      const Bounds &p = box[size_t(a)], &q = box[size_t(b)];
      if (count[size_t(b)] < kMinVoxels) continue;
      const Bounds& small = area(p) < area(q) ? p : q;
      const Bounds& large = area(p) < area(q) ? q : p;
      const Bounds both{small.min.cwiseMax(large.min), small.max.cwiseMin(large.max)};
      if (area(both) < kShare * area(small)) continue;
      const float below = std::min(p.max.z(), q.max.z()), above = std::max(p.min.z(), q.min.z());  // the gap
      if (above - below > kMaxGap || (above > below && support_between(below, above))) continue;
      joins.join(a, b);
    }
  return joins.relabel(labels);
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

// Whether the object is a remnant of the floor or a wall: most of its points within twice the plane's
// reach (the camera's noise beyond the inlier distance, a strip of wall seen between objects). A table
// top's remnants are not looked for: a low object on the table lies as close to it.
bool remnant(const SceneObject& o, const std::vector<Plane>& planes, const Vec3& sensor, const SceneParams& params) {
  const std::optional<float> floor = floor_height(planes);
  std::vector<const Plane*> room;
  for (const Plane& plane : planes)
    if (!is_level(plane) || level_height(plane) <= *floor + params.plane_distance_m) room.push_back(&plane);
  if (room.empty()) return false;
  size_t near = 0;
  for (const Vec3& p : o.points) {
    const float reach = 2.f * plane_reach(p, sensor, params);
    near += std::any_of(room.begin(), room.end(),
                        [&](const Plane* plane) { return std::abs(plane->normal.dot(p) + plane->offset) <= reach; });
  }
  return double(near) >= params.max_remnant_share * double(o.points.size());
}

bool keep(const SceneObject& o, const std::vector<Plane>& planes, const Vec3& sensor, const SceneParams& params) {
  const size_t n = o.indices.size();
  return n <= params.max_object_points &&
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

double frame_density(const Points& points, const Vec3& sensor) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Vec3& p : points)
    if (p.allFinite() && p != sensor) mean += (p - sensor).normalized().cast<double>();
  if (!(mean.norm() > 0)) return 0;
  const Vec3 axis = mean.normalized().cast<float>();
  const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
  // Cells of two degrees at the axis (wide enough that the pixels' lattice, at any angle to them, fills
  // each alike) on the plane one metre ahead, where a camera's pixels lie evenly, out to 60 degrees.
  constexpr float kCell = 0.0349208f;  // tan(2 degrees)
  constexpr int kHalf = 50;            // tan(60 degrees) / kCell, rounded up
  std::vector<uint32_t> cells(size_t(4 * kHalf * kHalf), 0);
  for (const Vec3& p : points) {
    if (!p.allFinite()) continue;
    const Vec3 d = p - sensor;
    const float ahead = d.dot(axis);
    if (!(ahead > 0)) continue;
    const int a = int(std::floor(d.dot(u) / ahead / kCell)) + kHalf, b = int(std::floor(d.dot(v) / ahead / kCell)) + kHalf;
    if (a >= 0 && a < 2 * kHalf && b >= 0 && b < 2 * kHalf) ++cells[size_t(a) * 2 * kHalf + size_t(b)];
  }
  std::erase(cells, 0u);
  if (cells.empty()) return 0;
  const auto mid = cells.begin() + std::ptrdiff_t(cells.size() / 2);
  std::nth_element(cells.begin(), mid, cells.end());
  return double(*mid) / 4;  // per square degree
}

SceneParams at_density(const SceneParams& params, double density_per_deg2) {
  if (!(params.reference_density_per_deg2 > 0) || !(density_per_deg2 > 0) ||
      !(density_per_deg2 < params.reference_density_per_deg2))
    return params;
  const double share = density_per_deg2 / params.reference_density_per_deg2;  // of the points
  SceneParams at = params;
  at.min_object_points = std::max<size_t>(std::min<size_t>(20, params.min_object_points),
                                          size_t(std::lround(double(params.min_object_points) * share)));
  // The camera's depth steps (a pixel's fraction of disparity) grow as its pixels widen: the range term of
  // the cluster tolerance with them. The 3 cm that parts objects stays.
  at.cluster_tolerance_per_m2 *= float(1 / std::sqrt(share));
  return at;
}

Expected<Scene> segment_scene(const Cloud& frame, const SceneParams& given) {
  if (Status s = check(given); !s) return s.error();
  const Voxels voxels = voxelise(frame.points, given.voxel_m);
  Scene scene;
  scene.finite_points = voxels.finite;
  SceneLabels labels(voxels.centroids.size(), 0);
  const Vec3 sensor = frame.sensor.value_or(Vec3::Zero());
  if (given.reference_density_per_deg2 > 0) scene.density_per_deg2 = frame_density(frame.points, sensor);
  const SceneParams params = at_density(given, scene.density_per_deg2);
  scene.min_object_points = params.min_object_points;
  scene.planes = remove_planes(voxels.centroids, sensor, params, labels);
  scene.planes = keep_room_and_supports(std::move(scene.planes), voxels.centroids, sensor, params, labels);
  int32_t clusters = cluster_voxels(voxels.centroids, sensor, params, labels);
  if (has_level_plane(scene)) {  // +z is up
    clusters = join_overlapping(voxels.centroids, clusters, scene.planes, labels);
    clusters = join_hidden(voxels.centroids, clusters, sensor, params, labels);
  }
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
