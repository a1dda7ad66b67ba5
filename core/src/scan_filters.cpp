#include "glimpse/scan_filters.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "glimpse/neighbourhoods.h"

namespace glimpse {

namespace {

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const Points& points, const std::vector<uint32_t>* subset = nullptr) {
  auto out = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  const size_t n = subset ? subset->size() : points.size();
  out->reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = points[subset ? (*subset)[i] : i];
    out->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  return out;
}

std::vector<uint32_t> finite_indices(const Points& points) {
  std::vector<uint32_t> idx;
  idx.reserve(points.size());
  for (uint32_t i = 0; i < points.size(); ++i)
    if (points[i].allFinite()) idx.push_back(i);
  return idx;
}

}  // namespace

Cloud remove_ground_plane(const Cloud& cloud, const ScanFilterParams& params, size_t* removed) {
  if (removed) *removed = 0;
  const std::vector<uint32_t> finite = finite_indices(cloud.points);
  if (finite.size() < 10) return cloud;
  float zmin = INFINITY;
  for (uint32_t i : finite) zmin = std::min(zmin, cloud.points[i].z());
  std::vector<uint32_t> band;  // the floor, if any, is among the lowest points
  for (uint32_t i : finite)
    if (cloud.points[i].z() <= zmin + params.ground_band_m) band.push_back(i);
  const size_t min_inliers = std::max<size_t>(10, size_t(std::ceil(params.min_ground_fraction * double(finite.size()))));
  if (band.size() < min_inliers) return cloud;

  pcl::SACSegmentation<pcl::PointXYZ> seg;  // fixed RANSAC seed (PCL's default 12345): deterministic
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(Eigen::Vector3f::UnitZ());
  seg.setEpsAngle(params.max_tilt_deg * std::numbers::pi_v<float> / 180.f);
  seg.setDistanceThreshold(params.ground_distance_m);
  seg.setMaxIterations(200);
  seg.setInputCloud(to_pcl(cloud.points, &band));
  pcl::PointIndices inliers;
  pcl::ModelCoefficients plane;
  seg.segment(inliers, plane);
  if (inliers.indices.size() < min_inliers || plane.values.size() != 4) return cloud;

  // Every point of the cloud within the inlier distance of the plane goes (or below it: under the floor
  // there is nothing but noise), not only the band's.
  Eigen::Vector4f abcd(plane.values[0], plane.values[1], plane.values[2], plane.values[3]);
  abcd /= abcd.head<3>().norm();
  if (abcd.z() < 0) abcd = -abcd;  // normal up
  size_t above = 0, below = 0;
  for (uint32_t i : finite) {
    const float d = abcd.head<3>().dot(cloud.points[i]) + abcd.w();
    above += d > params.ground_distance_m, below += d < -3 * params.ground_distance_m;
  }
  if (double(above) < std::max(30.0, 0.01 * double(finite.size())) || double(below) > 0.01 * double(finite.size()))
    return cloud;  // nothing stands on it, or something is under it: part of the object
  // A floor reaches out beyond what stands on it (in front and to both sides, seen from a sensor); a base
  // plate or a flange of the object does not, or on fewer sides.
  Eigen::Vector2f glo(INFINITY, INFINITY), ghi(-INFINITY, -INFINITY), olo = glo, ohi = ghi;
  for (uint32_t i : finite) {
    const Vec3& p = cloud.points[i];
    const bool g = abcd.head<3>().dot(p) + abcd.w() <= params.ground_distance_m;
    (g ? glo : olo) = (g ? glo : olo).cwiseMin(p.head<2>());
    (g ? ghi : ohi) = (g ? ghi : ohi).cwiseMax(p.head<2>());
  }
  const float margin = std::max(0.05f, 0.1f * (ohi - olo).maxCoeff());
  const int sides = (glo.x() < olo.x() - margin) + (glo.y() < olo.y() - margin) + (ghi.x() > ohi.x() + margin) +
                    (ghi.y() > ohi.y() + margin);
  if (sides < params.ground_min_sides) return cloud;
  Cloud out;
  out.sensor = cloud.sensor;
  out.points.reserve(cloud.points.size());
  for (const Vec3& p : cloud.points) {
    const float d = abcd.head<3>().dot(p) + abcd.w();
    if (p.allFinite() && d <= params.ground_distance_m) continue;
    out.points.push_back(p);
  }
  if (removed) *removed = cloud.points.size() - out.points.size();
  return out;
}

Cloud remove_isolated_points(const Cloud& cloud, float radius_spacings, int min_neighbours, size_t* removed) {
  if (removed) *removed = 0;
  const std::vector<uint32_t> finite = finite_indices(cloud.points);
  if (min_neighbours < 1 || finite.size() <= size_t(min_neighbours) + 1) return cloud;
  Points fin;
  for (uint32_t i : finite) fin.push_back(cloud.points[i]);
  const float spacing = median_knn_distance(KdTree(fin), 1);
  if (!(spacing > 0)) return cloud;
  pcl::RadiusOutlierRemoval<pcl::PointXYZ> ror;
  ror.setInputCloud(to_pcl(fin));
  ror.setRadiusSearch(radius_spacings * spacing);
  ror.setMinNeighborsInRadius(min_neighbours);
  pcl::Indices kept;
  ror.filter(kept);
  std::sort(kept.begin(), kept.end());  // the cloud's order
  Cloud out;
  out.sensor = cloud.sensor;
  out.points.reserve(kept.size());
  for (int k : kept) out.points.push_back(fin[size_t(k)]);
  if (removed) *removed = cloud.points.size() - out.points.size();
  return out;
}

Cloud voxel_downsample(const Cloud& cloud, float leaf_m) {
  const std::vector<uint32_t> finite = finite_indices(cloud.points);
  if (!(leaf_m > 0) || finite.empty()) return cloud;
  // VoxelGrid indexes voxels with 32-bit integers; a leaf too fine for the extent would overflow (PCL
  // then returns the input unchanged with a warning), so the leaf is at least extent / 2^20.
  Points fin;
  for (uint32_t i : finite) fin.push_back(cloud.points[i]);
  const Vec3 e = bounds(fin).extent();
  leaf_m = std::max(leaf_m, e.maxCoeff() / float(1 << 20));
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(to_pcl(fin));
  grid.setLeafSize(leaf_m, leaf_m, leaf_m);
  pcl::PointCloud<pcl::PointXYZ> out_pcl;
  grid.filter(out_pcl);
  Cloud out;
  out.sensor = cloud.sensor;
  out.points.reserve(out_pcl.size());
  for (const pcl::PointXYZ& p : out_pcl) out.points.emplace_back(p.x, p.y, p.z);
  return out;
}

double relative_density(const Points& points) {
  constexpr size_t k = 12;  // a square grid's 3rd ring of neighbours ends at 12: grids and random samples agree
  const std::vector<uint32_t> finite = finite_indices(points);
  if (finite.size() <= k) return 0;
  Points fin;
  for (uint32_t i : finite) fin.push_back(points[i]);
  const double extent = bounds(fin).extent().maxCoeff();
  const KdTree tree(fin);
  const double rk = median_knn_distance(tree, k);
  if (!(extent > 0) || !(rk > 0)) return 0;
  return double(k) / (std::numbers::pi * rk * rk) * extent * extent;
}

Cloud filter_scan(const Cloud& cloud, const ScanFilterParams& params, ScanFilterReport* report) {
  ScanFilterReport r;
  r.input = cloud.points.size();
  // Stray points first: one under the floor would otherwise define the lowest band.
  Cloud c = params.remove_outliers
                ? remove_isolated_points(cloud, params.outlier_radius_spacings, params.outlier_min_neighbours, &r.outliers)
                : cloud;
  if (params.remove_ground) c = remove_ground_plane(c, params, &r.ground);
  if (params.relative_density > 0 && relative_density(c.points) > 2 * params.relative_density) {
    const float leaf = bounds(c.points).extent().maxCoeff() / float(std::sqrt(params.relative_density));
    c = voxel_downsample(c, leaf);
    r.voxel_m = leaf;
  }
  r.kept = c.points.size();
  if (report) *report = r;
  return c;
}

}  // namespace glimpse
