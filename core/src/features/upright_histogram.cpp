#include "glimpse/features/upright_histogram.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace glimpse {

float shape_index(float k1, float k2) {
  // eq. 7 with atan2 (k1 - k2 >= 0), so an umbilic point (k1 == k2) needs no division.
  return 0.5f - std::atan2(k1 + k2, k1 - k2) / std::numbers::pi_v<float>;
}

namespace {

int clamp_bin(float value, int bins) { return std::clamp(static_cast<int>(value), 0, bins - 1); }

// Square-root scale: bins are finer near zero, where a prefix's top and axis are.
int sqrt_bin(float value, float max, int bins) {
  return clamp_bin(std::sqrt(std::max(0.f, value) / max) * static_cast<float>(bins), bins);
}

}  // namespace

Eigen::VectorXf upright_histogram(const Points& points, const std::vector<LocalSurface>& surfaces,
                                  const UprightHistogramParams& params) {
  Eigen::VectorXf h = Eigen::VectorXf::Zero(kUprightHistogramSize);
  const size_t n = std::min(points.size(), surfaces.size());
  double cx = 0, cy = 0;
  float top = -std::numeric_limits<float>::infinity();
  size_t valid = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!surfaces[i].valid) continue;
    cx += points[i].x();
    cy += points[i].y();
    top = std::max(top, points[i].z());
    ++valid;
  }
  if (valid == 0) return h;
  cx /= static_cast<double>(valid);
  cy /= static_cast<double>(valid);

  float* shape = h.data();
  float* orientation = shape + kShapeIndexBins * kCurvednessBins;
  float* profile = orientation + kElevationBins * kDepthBins;
  const float weight = 1.f / static_cast<float>(valid);
  for (size_t i = 0; i < n; ++i) {
    const LocalSurface& s = surfaces[i];
    if (!s.valid) continue;
    const Vec3& p = points[i];
    const float curvedness = std::sqrt(0.5f * (s.k1 * s.k1 + s.k2 * s.k2));
    const int c = curvedness < params.flat_curvedness
                      ? 0
                      : clamp_bin(std::log2(curvedness / params.flat_curvedness) + 1.f, kCurvednessBins);
    const int si = clamp_bin(shape_index(s.k1, s.k2) * kShapeIndexBins, kShapeIndexBins);
    shape[si * kCurvednessBins + c] += weight;

    const int depth = sqrt_bin(top - p.z(), params.max_depth_m, kDepthBins);
    const int elevation = clamp_bin((s.normal.z() + 1.f) * 0.5f * kElevationBins, kElevationBins);
    orientation[elevation * kDepthBins + depth] += weight;

    const float radial = static_cast<float>(std::hypot(p.x() - cx, p.y() - cy));
    profile[sqrt_bin(radial, params.max_radius_m, kRadialBins) * kDepthBins + depth] += weight;
  }
  return h;
}

Eigen::VectorXf visible_size(const Points& points) {
  Eigen::VectorXf out = Eigen::VectorXf::Zero(kVisibleSizeSize);
  if (points.empty()) return out;
  double zmin = INFINITY, zmax = -INFINITY, cx = 0, cy = 0;
  for (const Vec3& p : points) {
    zmin = std::min(zmin, double(p.z())), zmax = std::max(zmax, double(p.z()));
    cx += p.x(), cy += p.y();
  }
  cx /= double(points.size()), cy /= double(points.size());
  double sxx = 0, sxy = 0, syy = 0;
  for (const Vec3& p : points) {
    const double x = p.x() - cx, y = p.y() - cy;
    sxx += x * x, sxy += x * y, syy += y * y;
  }
  // Principal axis of the 2x2 covariance: angle 1/2 atan2(2 sxy, sxx - syy).
  const double a = 0.5 * std::atan2(2 * sxy, sxx - syy);
  const double ux = std::cos(a), uy = std::sin(a);
  double lo1 = INFINITY, hi1 = -INFINITY, lo2 = INFINITY, hi2 = -INFINITY;
  for (const Vec3& p : points) {
    const double x = p.x() - cx, y = p.y() - cy;
    const double s1 = x * ux + y * uy, s2 = -x * uy + y * ux;
    lo1 = std::min(lo1, s1), hi1 = std::max(hi1, s1), lo2 = std::min(lo2, s2), hi2 = std::max(hi2, s2);
  }
  const double e1 = hi1 - lo1, e2 = hi2 - lo2;
  out << float(zmax - zmin), float(std::max(e1, e2)), float(std::min(e1, e2));
  return out;
}

}  // namespace glimpse
