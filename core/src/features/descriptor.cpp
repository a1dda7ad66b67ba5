#include "glimpse/features/descriptor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace glimpse {

float modified_shape_index(float k1, float k2) {
  // eq. 7-8 with atan2, so k1 == k2 (umbilic) gives 1/2 rather than a division by zero.
  return std::abs(std::atan2(k1 + k2, k1 - k2)) / std::numbers::pi_v<float>;
}

std::array<float, 8> pfh8(const std::vector<Vec3>& points, const std::vector<Vec3>& normals) {
  std::array<float, 8> h{};
  size_t pairs = 0;
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      Vec3 d = points[j] - points[i];
      const float len = d.norm();
      if (len <= 0) continue;
      d /= len;
      // Source: the point whose normal makes the smaller angle with the connecting line (Rusu 2008).
      Vec3 ns = normals[i], nt = normals[j];
      if (std::abs(ns.dot(d)) < std::abs(nt.dot(d))) {
        std::swap(ns, nt);
        d = -d;
      }
      // eq. 5: Darboux frame u = n_s, v = u x d, w = u x v.
      const Vec3 u = ns;
      Vec3 v = u.cross(d);
      const float vn = v.norm();
      if (vn <= 1e-12f) continue;
      v /= vn;
      const Vec3 w = u.cross(v);
      // eq. 6 (with alpha = v . n_t as in Rusu's definition the paper cites).
      const float alpha = v.dot(nt);
      const float phi = u.dot(d);
      // theta = atan2(w . n_t, u . n_t) >= 0, told from the signs alone (atan2 keeps the sign of
      // its first argument, -0 included, and gives -pi for (-0, negative)).
      const float ty = w.dot(nt), tx = u.dot(nt);
      const bool theta_nonnegative = ty > 0 || (ty == 0 && (!std::signbit(ty) || !std::signbit(tx)));
      const int bin = (alpha >= 0 ? 4 : 0) + (phi >= 0 ? 2 : 0) + (theta_nonnegative ? 1 : 0);
      h[bin] += 1.f;
      ++pairs;
    }
  }
  if (pairs)
    for (float& b : h) b /= static_cast<float>(pairs);
  return h;
}

float descriptor_radius(const Keypoint& kp, float r, const DescriptorParams& params) {
  if (params.characteristic_scale_supports <= 0) return r;
  return std::clamp(kp.characteristic_radius, r, std::max(1.f, params.characteristic_scale_supports) * r);
}

float descriptor_reach(float r, const DescriptorParams& params) {
  const float hood = params.characteristic_scale_supports > 0 ? std::max(1.f, params.characteristic_scale_supports) * r : r;
  return std::max(1.f, params.large_window_supports) * hood;
}

Descriptor local_descriptor(const NeighbourIndex& tree, const std::vector<LocalSurface>& surfaces, const Keypoint& kp,
                            float support_r, const DescriptorParams& params, std::vector<Neighbour>& nb) {
  const float r = descriptor_radius(kp, support_r, params);
  Descriptor d = Descriptor::Zero();
  const Points& pts = tree.points();
  const LocalSurface& s = surfaces[kp.index];

  tree.radius(kp.position, r, nb);  // ascending index
  std::vector<Vec3> hood;
  hood.reserve(nb.size());
  for (const Neighbour& q : nb) hood.push_back(pts[q.index]);

  // PFH over the neighbourhood with valid normals, subsampled evenly when large.
  std::vector<Vec3> p, n;
  const size_t step = std::max<size_t>(1, (nb.size() + params.max_pfh_points - 1) / std::max<size_t>(params.max_pfh_points, 1));
  for (size_t i = 0; i < nb.size(); i += step) {
    const LocalSurface& q = surfaces[nb[i].index];
    if (!q.valid) continue;
    p.push_back(pts[nb[i].index]);
    n.push_back(q.normal);
  }
  const std::array<float, 8> h = pfh8(p, n);
  for (int i = 0; i < 8; ++i) d[kPfhFirst + i] = h[i];

  // eq. 4: angle between the small-window normal and the large-window one (sign-free).
  const Vec3 large = pca_normal(tree, kp.position, params.large_window_supports * r, nb);
  d[kNormalAngle] = large.isZero() ? 0.f : std::acos(std::clamp(std::abs(s.normal.dot(large)), 0.f, 1.f));
  d[kShapeIndex] = modified_shape_index(s.k1, s.k2);            // eq. 8
  d[kRho2] = s.lambda_max > 0 ? 2.f / std::sqrt(s.lambda_max) : 0.f;  // eq. 9
  d[kHullVolume] = static_cast<float>(convex_hull_volume(hood));
  return d;
}

}  // namespace glimpse
