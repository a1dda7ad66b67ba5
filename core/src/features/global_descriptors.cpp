// VFH (sec. 3.1) over plain clouds, and PCL's own VFH and ESF pipelines as references; ESF is in
// global_descriptors_esf.cpp.
#include "glimpse/features/global_descriptors.h"
#include "features/global_descriptors_common.h"

#include <pcl/features/esf.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/features/vfh.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace glimpse {
namespace global_internal {

Status validate(const Cloud& cloud, const char* who) {
  const size_t n = cloud.points.size();
  if (n < static_cast<size_t>(kMinGlobalDescriptorPoints))
    return invalid_argument(std::string(who) + ": needs at least " +
                            std::to_string(kMinGlobalDescriptorPoints) + " points, got " + std::to_string(n));
  for (const Vec3& p : cloud.points)
    if (!p.allFinite()) return invalid_argument(std::string(who) + ": cloud has NaN or Inf coordinates");
  if (cloud.sensor && !cloud.sensor->allFinite())
    return invalid_argument(std::string(who) + ": sensor position has NaN or Inf coordinates");
  if (bounds(cloud.points).extent().maxCoeff() < 1e-6f)
    return invalid_argument(std::string(who) + ": degenerate cloud, all points coincide");
  return {};
}

Eigen::Vector3d centroid(const Points& points) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Vec3& p : points) c += p.cast<double>();
  return c / static_cast<double>(points.size());
}

}  // namespace global_internal

namespace {

using global_internal::centroid;
using global_internal::validate;
using PclCloud = pcl::PointCloud<pcl::PointXYZ>;
using PclNormals = pcl::PointCloud<pcl::Normal>;

PclCloud::Ptr to_pcl(const Points& points) {
  PclCloud::Ptr pc(new PclCloud);
  pc->reserve(points.size());
  for (const Vec3& p : points) pc->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return pc;
}

// 4 x the median nearest-neighbour spacing over a fixed-stride sample of up to 2000 points.
float automatic_normal_radius(const PclCloud& pc, pcl::search::KdTree<pcl::PointXYZ>& tree) {
  const size_t stride = std::max<size_t>(1, pc.size() / 2000);
  std::vector<float> spacing;
  pcl::Indices idx(2);
  std::vector<float> d2(2);
  for (size_t i = 0; i < pc.size(); i += stride) {
    if (tree.nearestKSearch(pc[i], 2, idx, d2) == 2 && d2[1] > 0) spacing.push_back(std::sqrt(d2[1]));
  }
  if (spacing.empty()) return 0;
  auto mid = spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2);
  std::nth_element(spacing.begin(), mid, spacing.end());
  return 4.0f * *mid;
}

}  // namespace

namespace {
// Sec. 3.1: VFH with the viewpoint direction and the surface shape (size) component, over the points
// in `kept` (those with a normal).
Expected<Eigen::VectorXf> vfh_signature(const Cloud& cloud, const PclCloud::Ptr& pc, const PclNormals::Ptr& normals,
                                        const pcl::IndicesPtr& kept,
                                        const pcl::search::KdTree<pcl::PointXYZ>::Ptr& tree,
                                        const GlobalDescriptorParams& params) {
  pcl::VFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> est;
  est.setInputCloud(pc);
  est.setIndices(kept);
  est.setInputNormals(normals);
  // VFH never searches, but pcl::Feature::initCompute builds its tree over the input unless the tree
  // already holds that cloud: given one over the cloud's first kept point, nothing is built (a 10k-point
  // view: 2.42 -> 1.50 ms, bench_global_descriptors BM_GlimpseVfhWithNormals), the signature is the same.
  if (tree->getInputCloud() != pc) tree->setInputCloud(pc, pcl::IndicesConstPtr(new pcl::Indices{kept->front()}));
  est.setSearchMethod(tree);
  const Vec3 vp = cloud.sensor.value_or(Vec3::Zero());
  est.setViewPoint(vp.x(), vp.y(), vp.z());
  est.setFillSizeComponent(params.fill_size_component);
  pcl::PointCloud<pcl::VFHSignature308> out;
  est.compute(out);
  if (out.size() != 1) return internal_error("vfh: pcl::VFHEstimation produced no signature");
  Eigen::VectorXf h = Eigen::Map<const Eigen::VectorXf>(out[0].histogram, kVfhSize);
  if (!h.allFinite()) return internal_error("vfh: non-finite histogram");
  return h;
}
}  // namespace

Expected<Eigen::VectorXf> vfh(const Cloud& cloud, const GlobalDescriptorParams& params) {
  if (Status s = validate(cloud, "vfh"); !s) return s.error();
  if (!std::isfinite(params.normal_radius_m)) return invalid_argument("vfh: normal_radius_m is not finite");
  PclCloud::Ptr pc = to_pcl(cloud.points);
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(pc);
  float radius = params.normal_radius_m;
  if (radius <= 0) radius = automatic_normal_radius(*pc, *tree);
  if (!(radius > 0)) return invalid_argument("vfh: cannot derive a normal radius (duplicate points only)");

  // Sec. 3.2.4: PCA normals, oriented toward the camera when the viewpoint is known.
  // Each normal depends only on its own neighbourhood: identical for any number of threads. One
  // thread takes the serial estimator (same arithmetic, ~15% faster than the OpenMP one on 1 thread).
  PclNormals::Ptr normals(new PclNormals);
  pcl::IndicesPtr kept(new pcl::Indices);
  const Eigen::Vector3d c = centroid(cloud.points);
  auto estimate_normals = [&](float r) {
    auto estimate = [&](auto& ne) {
      ne.setInputCloud(pc);
      ne.setSearchMethod(tree);
      ne.setRadiusSearch(r);
      if (cloud.sensor) ne.setViewPoint(cloud.sensor->x(), cloud.sensor->y(), cloud.sensor->z());
      ne.compute(*normals);
    };
    if (params.threads == 1) {
      pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
      estimate(ne);
    } else {
      pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(static_cast<unsigned>(std::max(0, params.threads)));
      estimate(ne);
    }
    // Undefined normals (< 3 neighbours) would turn VFH's sums into NaN: leave their points out
    // through the index list (same result as a filtered copy, without rebuilding the search tree).
    kept->clear();
    if (normals->size() != pc->size()) return;
    kept->reserve(pc->size());
    for (size_t i = 0; i < pc->size(); ++i) {
      pcl::Normal& n = (*normals)[i];
      if (!std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) || !std::isfinite(n.normal_z)) continue;
      if (!cloud.sensor) {  // no viewpoint: orient away from the centroid
        const Eigen::Vector3d out = cloud.points[i].cast<double>() - c;
        if (out.dot(Eigen::Vector3d(n.normal_x, n.normal_y, n.normal_z)) < 0) {
          n.normal_x = -n.normal_x;
          n.normal_y = -n.normal_y;
          n.normal_z = -n.normal_z;
        }
      }
      kept->push_back(static_cast<pcl::index_t>(i));
    }
  };
  estimate_normals(radius);
  if (normals->size() != pc->size()) return internal_error("vfh: normal estimation failed");
  // A fixed radius too small for a sparse scan (a far or large object) leaves most points without a
  // normal: then the density decides, as with normal_radius_m <= 0, rather than failing the scan.
  if (params.normal_radius_m > 0 && kept->size() * 2 < pc->size()) {
    const float automatic = automatic_normal_radius(*pc, *tree);
    if (automatic > radius) {
      radius = automatic;
      estimate_normals(radius);
      if (normals->size() != pc->size()) return internal_error("vfh: normal estimation failed");
    }
  }
  normals->is_dense = kept->size() == pc->size();
  if (kept->size() < static_cast<size_t>(kMinGlobalDescriptorPoints))
    return invalid_argument("vfh: only " + std::to_string(kept->size()) + " of " + std::to_string(pc->size()) +
                            " points have a normal within " + std::to_string(radius) +
                            " m; increase normal_radius_m");
  return vfh_signature(cloud, pc, normals, kept, tree, params);
}

Expected<Eigen::VectorXf> vfh_with_normals(const Cloud& cloud, const std::vector<Vec3>& normals,
                                           const GlobalDescriptorParams& params) {
  if (Status s = validate(cloud, "vfh"); !s) return s.error();
  if (normals.size() != cloud.points.size()) return invalid_argument("vfh: one normal per point is needed");
  PclCloud::Ptr pc = to_pcl(cloud.points);
  PclNormals::Ptr pn(new PclNormals);
  pn->resize(pc->size());
  pcl::IndicesPtr kept(new pcl::Indices);
  kept->reserve(pc->size());
  for (size_t i = 0; i < normals.size(); ++i) {
    const Vec3& n = normals[i];
    (*pn)[i].normal_x = n.x(), (*pn)[i].normal_y = n.y(), (*pn)[i].normal_z = n.z();
    if (n.allFinite() && n.squaredNorm() > 0.5f) kept->push_back(static_cast<pcl::index_t>(i));
  }
  pn->is_dense = kept->size() == pc->size();
  if (kept->size() < static_cast<size_t>(kMinGlobalDescriptorPoints))
    return invalid_argument("vfh: only " + std::to_string(kept->size()) + " of " + std::to_string(pc->size()) +
                            " points have a normal");
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  return vfh_signature(cloud, pc, pn, kept, tree, params);
}


// ---- PCL's pipelines, unchanged

namespace pcl_reference {

namespace {
// pcl::VFHEstimation as a user writes it; `tree` null: PCL builds its own.
Expected<Eigen::VectorXf> plain_vfh(const Cloud& cloud, const PclCloud::Ptr& pc, const PclNormals::Ptr& normals,
                                    const pcl::search::KdTree<pcl::PointXYZ>::Ptr& tree) {
  pcl::VFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> est;
  est.setInputCloud(pc);
  est.setInputNormals(normals);
  if (tree) est.setSearchMethod(tree);
  if (cloud.sensor) est.setViewPoint(cloud.sensor->x(), cloud.sensor->y(), cloud.sensor->z());
  est.setFillSizeComponent(true);
  pcl::PointCloud<pcl::VFHSignature308> out;
  est.compute(out);
  if (out.size() != 1) return internal_error("pcl_reference: VFHEstimation gave no signature");
  return Eigen::VectorXf(Eigen::Map<const Eigen::VectorXf>(out[0].histogram, kVfhSize));
}
}  // namespace

Expected<Eigen::VectorXf> vfh(const Cloud& cloud, float normal_radius_m) {
  PclCloud::Ptr pc = to_pcl(cloud.points);
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(pc);
  ne.setSearchMethod(tree);
  ne.setRadiusSearch(normal_radius_m);
  if (cloud.sensor) ne.setViewPoint(cloud.sensor->x(), cloud.sensor->y(), cloud.sensor->z());
  PclNormals::Ptr normals(new PclNormals);
  ne.compute(*normals);
  return plain_vfh(cloud, pc, normals, tree);
}

Expected<Eigen::VectorXf> vfh_with_normals(const Cloud& cloud, const std::vector<Vec3>& normals) {
  if (normals.size() != cloud.points.size()) return invalid_argument("pcl_reference::vfh_with_normals: one normal per point");
  PclCloud::Ptr pc = to_pcl(cloud.points);
  PclNormals::Ptr pn(new PclNormals);
  pn->resize(pc->size());
  for (size_t i = 0; i < normals.size(); ++i)
    (*pn)[i].normal_x = normals[i].x(), (*pn)[i].normal_y = normals[i].y(), (*pn)[i].normal_z = normals[i].z();
  return plain_vfh(cloud, pc, pn, nullptr);
}

Expected<Eigen::VectorXf> esf(const Cloud& cloud) {
  if (Status s = validate(cloud, "pcl_reference::esf"); !s) return s.error();  // PCL loops forever otherwise
  PclCloud::Ptr pc = to_pcl(cloud.points);
  pcl::ESFEstimation<pcl::PointXYZ, pcl::ESFSignature640> est;
  est.setInputCloud(pc);
  pcl::PointCloud<pcl::ESFSignature640> out;
  est.compute(out);
  if (out.size() != 1) return internal_error("pcl_reference::esf: no signature");
  return Eigen::VectorXf(Eigen::Map<const Eigen::VectorXf>(out[0].histogram, kEsfSize));
}

}  // namespace pcl_reference
}  // namespace glimpse
