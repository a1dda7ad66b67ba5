// The zoo's primitives (zoo_builder.h), each an even grid of triangles at the builder's spacing.
#include "views/zoo_builder.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "glimpse/spatial_hash.h"

namespace glimpse::zoo_internal {

void Builder::box(const Vec3& centre, const Vec3& size, const Mat3& rot) {
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-0.5f, 0.5f}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      grid(steps(size[u]), steps(size[v]), [&](float s, float t) {
        Vec3 p;
        p[axis] = side * size[axis];
        p[u] = (s - 0.5f) * size[u];
        p[v] = (t - 0.5f) * size[v];
        return Vec3(centre + rot * p);
      });
    }
}

void Builder::beam(const Vec3& a, const Vec3& b, float w, float d, float roll) {
  const Mat3 r = Eigen::Quaternionf::FromTwoVectors(Vec3::UnitZ(), b - a).toRotationMatrix() * rot_z(roll);
  box(0.5f * (a + b), Vec3(w, d, (b - a).norm()), r);
}

void Builder::ellipsoid(const Vec3& centre, const Vec3& radii, const Mat3& rot) {
  const float r = radii.maxCoeff();
  grid(steps(2 * kPi * r, 8), steps(kPi * r, 4), [&](float u, float v) {
    const float th = 2 * kPi * u, ph = kPi * (v - 0.5f);
    return Vec3(centre + rot * Vec3(radii.x() * std::cos(ph) * std::cos(th),
                                    radii.y() * std::cos(ph) * std::sin(th), radii.z() * std::sin(ph)));
  });
}

void Builder::extrusion(const Vec3& centre, const Mat3& rot, const std::function<float(float)>& radius,
                        float r_max, float height, float hole, float top_scale, int min_segments) {
  const int nt = steps(2 * kPi * r_max, min_segments), nz = steps(height), nr = steps(r_max - hole);
  auto at = [&](float r, float th, float z) {
    return Vec3(centre + rot * Vec3(r * std::cos(th), r * std::sin(th), z));
  };
  auto scale = [&](float v) { return 1 + (top_scale - 1) * v; };
  grid(nt, nz, [&](float u, float v) {
    return at(radius(2 * kPi * u) * scale(v), 2 * kPi * u, (v - 0.5f) * height);
  });
  if (hole > 0)
    grid(nt, nz, [&](float u, float v) { return at(hole * scale(v), 2 * kPi * u, (v - 0.5f) * height); });
  for (float end : {0.f, 1.f})
    grid(nt, nr, [&](float u, float v) {
      const float th = 2 * kPi * u;
      return at(scale(end) * (hole + v * (radius(th) - hole)), th, (end - 0.5f) * height);
    });
}

void Builder::frustum(const Vec3& a, const Vec3& b, float ra, float rb, float hole) {
  const Mat3 r = Eigen::Quaternionf::FromTwoVectors(Vec3::UnitZ(), b - a).toRotationMatrix();
  const float rr = std::max(ra, 1e-4f);
  extrusion(0.5f * (a + b), r, [rr](float) { return rr; }, rr, (b - a).norm(), hole, rb / rr);
}

void Builder::capsule(const Vec3& a, const Vec3& b, float ra, float rb) {
  frustum(a, b, ra, rb);
  ellipsoid(a, Vec3::Constant(ra));
  ellipsoid(b, Vec3::Constant(rb));
}

void Builder::torus(const Vec3& centre, const Mat3& rot, float R, float r, float sweep) {
  grid(steps(sweep * (R + r), 6), steps(2 * kPi * r, 8), [&](float u, float v) {
    const float th = sweep * u, ph = 2 * kPi * v;
    const float rr = R + r * std::cos(ph);
    return Vec3(centre + rot * Vec3(rr * std::cos(th), rr * std::sin(th), r * std::sin(ph)));
  });
}

Mesh Builder::finish() {
  const double q = 1e-3 * h_;
  std::unordered_map<CellKey, int, CellKeyHash> index;
  std::vector<int> remap(mesh_.vertices.size());
  Mesh out;
  for (size_t i = 0; i < mesh_.vertices.size(); ++i) {
    const Vec3& p = mesh_.vertices[i];
    const CellKey key{std::lround(p.x() / q), std::lround(p.y() / q), std::lround(p.z() / q)};  // nearest, not floor
    const auto [it, added] = index.emplace(key, int(out.vertices.size()));
    if (added) out.vertices.push_back(p);
    remap[i] = it->second;
  }
  for (const Eigen::Vector3i& f : mesh_.faces) {
    const Eigen::Vector3i g(remap[f[0]], remap[f[1]], remap[f[2]]);
    if (g[0] != g[1] && g[1] != g[2] && g[0] != g[2]) out.faces.push_back(g);
  }
  return out;
}

}  // namespace glimpse::zoo_internal
