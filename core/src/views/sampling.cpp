// Points from a mesh (sec. 3.4).
#include "glimpse/views/sampling.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "glimpse/random.h"

namespace glimpse {

namespace {

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cast<double>().cross((c - a).cast<double>()).norm();
}

}  // namespace

Cloud mesh_vertices(const Mesh& mesh) { return Cloud{mesh.vertices, std::nullopt, {}}; }

double surface_area(const Mesh& mesh) {
  double total = 0;
  for (const Eigen::Vector3i& f : mesh.faces)
    total += triangle_area(mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]);
  return total;
}

Cloud sample_surface(const Mesh& mesh, double points_per_m2, uint64_t seed) {
  constexpr double kMaxSamples = 50e6;
  Cloud cloud;
  std::vector<double> cumulative;
  cumulative.reserve(mesh.faces.size());
  double total = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const double a = triangle_area(mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]);
    total += std::isfinite(a) ? a : 0.0;
    cumulative.push_back(total);
  }
  if (!(total > 0) || !(points_per_m2 > 0)) return cloud;
  const auto n = static_cast<size_t>(std::llround(std::min(total * points_per_m2, kMaxSamples)));
  cloud.points.reserve(n);
  std::mt19937_64 rng(seed);
  for (size_t i = 0; i < n; ++i) {
    const double pick = uniform01(rng) * total;
    size_t t = std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin();
    t = std::min(t, cumulative.size() - 1);
    const Eigen::Vector3i& f = mesh.faces[t];
    // Uniform point in a triangle: Osada, Funkhouser, Chazelle & Dobkin 2002, eq. 1.
    const double r1 = std::sqrt(uniform01(rng)), r2 = uniform01(rng);
    const Eigen::Vector3d p = (1 - r1) * mesh.vertices[f[0]].cast<double>() +
                              r1 * (1 - r2) * mesh.vertices[f[1]].cast<double>() +
                              r1 * r2 * mesh.vertices[f[2]].cast<double>();
    cloud.points.push_back(p.cast<float>());
  }
  return cloud;
}

uint64_t object_seed(uint64_t seed, std::string_view key) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a: std::hash differs between standard libraries
  for (char c : key) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  return splitmix64(seed, h);
}

Points object_cloud(const Mesh& mesh, size_t points, uint64_t seed) {
  const double area = points ? surface_area(mesh) : 0.0;
  return area > 0 ? sample_surface(mesh, double(points) / area, seed).points : mesh_vertices(mesh).points;
}

}  // namespace glimpse
