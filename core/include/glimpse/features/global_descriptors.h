// Global descriptors of a whole (partial) cloud: the paper's VFH baseline (sec. 3.1) and ESF.
// Callers pass a plain Cloud; PCL stays inside the .cpp. Both are deterministic: the same cloud and
// parameters give a bit-identical vector whatever the thread count.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

inline constexpr int kVfhSize = 308;  // 45 x (f1, f2, f3, size) + 128 viewpoint bins, PCL's layout
inline constexpr int kEsfSize = 640;  // 10 x 64 bins: A3 in/out/mix, D3 in/out/mix, D2 in/out/mix/ratio
inline constexpr int kMinGlobalDescriptorPoints = 10;

struct GlobalDescriptorParams {
  // Radius (metres) of the neighbourhood for PCA normals. <= 0: automatic, 4 x the median
  // nearest-neighbour spacing of the cloud (about 12 to 50 neighbours on a regularly sampled surface).
  float normal_radius_m = 0.03f;
  // VFH's shape-distribution component (distances to the centroid, in cm bins 0..44 as in PCL: objects
  // wider than ~0.9 m saturate its last bin). false leaves those 45 bins at zero.
  bool fill_size_component = true;
  // Threads for normal estimation (1: PCL's serial estimator; else its OpenMP one; 0 = all cores).
  // The output is bit-identical for any value.
  int threads = 1;
};

// Viewpoint Feature Histogram (Rusu et al. 2010) via pcl::VFHEstimation, bins normalised as PCL does
// (each of the first four 45-bin blocks sums to ~100, the viewpoint block to 100).
// Normals: PCA over normal_radius_m, oriented toward cloud.sensor when set, else away from the
// centroid; points whose normal is undefined (< 3 neighbours) are dropped. When a fixed
// normal_radius_m leaves more than half the points without a normal (a sparse scan), the automatic
// radius is used instead if it is larger. The viewpoint component
// uses cloud.sensor, else the origin (PCL's default: clouds in the sensor frame).
// Errors (kInvalidArgument): fewer than kMinGlobalDescriptorPoints points, NaN/Inf coordinates, all
// points coincident, or too few points with a defined normal even at the automatic radius.
// Never returns a vector with NaN or Inf.
Expected<Eigen::VectorXf> vfh(const Cloud& cloud, const GlobalDescriptorParams& params = {});
// The same over given normals, one per point, already oriented (a zero normal: undefined, the point is
// left out): the recogniser passes its local surfaces' normals (PCA over the support radius r, the one
// density estimate every radius derives from), so nothing is estimated twice. normal_radius_m unused.
Expected<Eigen::VectorXf> vfh_with_normals(const Cloud& cloud, const std::vector<Vec3>& normals,
                                           const GlobalDescriptorParams& params = {});

// Ensemble of Shape Functions (Wohlkinger & Vincze 2011): PCL's ESFEstimation algorithm and histogram
// layout, re-implemented with a seeded std::mt19937_64 (PCL's calls srand(time) and rand(), so it is
// neither reproducible nor thread-safe) and a per-call voxel grid. Sums to 1. Rotation invariant;
// ignores cloud.sensor. Same errors as vfh(), plus a cloud with no non-degenerate triangle (collinear).
Expected<Eigen::VectorXf> esf(const Cloud& cloud, uint64_t seed = 1);

// PCL's own pipelines as a user would write them, unchanged, for tests and benchmarks to compare
// against. Not for production use.
namespace pcl_reference {
// pcl::NormalEstimation (radius, viewpoint = sensor or origin) + pcl::VFHEstimation, no NaN filtering.
Expected<Eigen::VectorXf> vfh(const Cloud& cloud, float normal_radius_m);
// pcl::VFHEstimation over the given normals (each point's, all kept), PCL building its own search tree.
Expected<Eigen::VectorXf> vfh_with_normals(const Cloud& cloud, const std::vector<Vec3>& normals);
// pcl::ESFEstimation: seeds rand() from time(); NOT reproducible, NOT thread-safe.
Expected<Eigen::VectorXf> esf(const Cloud& cloud);
}  // namespace pcl_reference

}  // namespace glimpse
