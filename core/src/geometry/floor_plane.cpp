#include "glimpse/geometry/floor_plane.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/console/print.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string>

namespace glimpse {

std::optional<Plane> fit_plane(const Points& points, const std::vector<uint32_t>& subset, const PlaneFitParams& params,
                               std::vector<uint32_t>* inliers) {
  if (inliers) inliers->clear();
  if (subset.size() < 3) return std::nullopt;
  // PCL reports "no model found" (a normal outcome here) on stderr; a service's log is no place for it.
  static const bool quiet = [] {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    return true;
  }();
  (void)quiet;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->reserve(subset.size());
  for (uint32_t i : subset) cloud->push_back(pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z()));
  pcl::SACSegmentation<pcl::PointXYZ> seg;  // fixed RANSAC seed (PCL's default 12345): deterministic
  seg.setOptimizeCoefficients(true);
  seg.setModelType(params.axis ? pcl::SACMODEL_PERPENDICULAR_PLANE : pcl::SACMODEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  if (params.axis) {
    seg.setAxis(*params.axis);
    seg.setEpsAngle(params.max_angle_deg * std::numbers::pi_v<float> / 180.f);
  }
  seg.setDistanceThreshold(params.distance_m);
  seg.setMaxIterations(params.max_iterations);
  seg.setInputCloud(cloud);
  pcl::PointIndices found;
  pcl::ModelCoefficients coefficients;
  seg.segment(found, coefficients);
  if (found.indices.empty() || coefficients.values.size() != 4) return std::nullopt;
  Eigen::Vector4f abcd(coefficients.values[0], coefficients.values[1], coefficients.values[2], coefficients.values[3]);
  abcd /= abcd.head<3>().norm();
  if (!abcd.allFinite()) return std::nullopt;
  if (inliers)
    for (int k : found.indices) inliers->push_back(subset[size_t(k)]);
  return Plane{abcd.head<3>(), abcd.w(), found.indices.size()};
}

namespace {

// Every step-th finite point, at most max_points of them: RANSAC's cost grows with the points it scores,
// a plane's normal hardly with them.
std::vector<uint32_t> even_finite_subset(const Points& points, size_t max_points) {
  std::vector<uint32_t> finite;
  finite.reserve(points.size());
  for (uint32_t i = 0; i < points.size(); ++i)
    if (points[i].allFinite()) finite.push_back(i);
  const size_t step = std::max<size_t>(1, (finite.size() + max_points - 1) / std::max<size_t>(1, max_points));
  std::vector<uint32_t> subset;
  for (size_t k = 0; k < finite.size(); k += step) subset.push_back(finite[k]);
  return subset;
}

}  // namespace

Expected<Vec3> floor_up(const Cloud& cloud, const FloorParams& params) {
  std::vector<uint32_t> remaining = even_finite_subset(cloud.points, params.max_points);
  if (remaining.size() < 3)
    return invalid_argument("no floor: " + std::to_string(remaining.size()) + " finite points, a plane needs 3");
  const Vec3 sensor = cloud.sensor.value_or(Vec3::Zero());
  const Vec3 image_up = cloud.frame && cloud.frame->up.norm() > 0 ? Vec3(cloud.frame->up.normalized()) : Vec3(-Vec3::UnitY());
  const float min_cos = std::cos(params.max_tilt_deg * std::numbers::pi_v<float> / 180.f);
  const size_t min_inliers = std::max<size_t>(3, size_t(std::ceil(params.min_fraction * double(remaining.size()))));
  const PlaneFitParams fit{params.distance_m, 1000, std::nullopt, 90.f};
  std::vector<uint32_t> inliers, rest;
  // The largest planes first (a wall or the table's front may outnumber the floor): the first that the
  // camera looks down on is the floor.
  for (int k = 0; k < params.max_planes; ++k) {
    const std::optional<Plane> plane = fit_plane(cloud.points, remaining, fit, &inliers);
    if (!plane || plane->inliers < min_inliers) break;
    const Vec3 up = plane->normal.dot(sensor) + plane->offset >= 0 ? plane->normal : Vec3(-plane->normal);
    if (up.dot(image_up) >= min_cos) return up;
    std::sort(inliers.begin(), inliers.end());  // a subsequence of `remaining`, which ascends
    rest.clear();
    std::set_difference(remaining.begin(), remaining.end(), inliers.begin(), inliers.end(), std::back_inserter(rest));
    remaining.swap(rest);
  }
  return invalid_argument("no floor: no plane holding " + std::to_string(int(std::lround(params.min_fraction * 100))) +
                          " % of the points that the camera looks down on (within " +
                          std::to_string(int(std::lround(params.max_tilt_deg))) + " degrees of the image's up)");
}

}  // namespace glimpse
