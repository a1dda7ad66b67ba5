// Single 2.5D views from full models (sec. 3.4) and the top-to-bottom exploring sequence (sec. 4).
#include "glimpse/views.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <locale>
#include <random>
#include <sstream>
#include <string>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "random.h"

namespace glimpse {
namespace {

constexpr double kPi = 3.14159265358979323846;

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cast<double>().cross((c - a).cast<double>()).norm();
}

template <class F>
Mesh transform_vertices(Mesh mesh, F&& f) {
  for (Vec3& v : mesh.vertices) v = f(v);
  return mesh;
}

}  // namespace

Cloud mesh_vertices(const Mesh& mesh) { return Cloud{mesh.vertices, std::nullopt}; }

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

Expected<Vec3> parse_up(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  const std::string original(text);
  bool negative = false;
  std::string_view axis = text;
  if (!axis.empty() && (axis.front() == '+' || axis.front() == '-')) {
    negative = axis.front() == '-';
    axis.remove_prefix(1);
  }
  if (axis.size() == 1) {
    const int a = std::tolower(static_cast<unsigned char>(axis[0])) - 'x';
    if (a >= 0 && a < 3) return Vec3((negative ? -1.f : 1.f) * Vec3::Unit(a));
  }
  // Three numbers separated by blanks.
  std::istringstream in(original);
  in.imbue(std::locale::classic());
  double v[3];
  std::string rest;
  if (in >> v[0] >> v[1] >> v[2] && !(in >> rest)) {
    const Eigen::Vector3d d(v[0], v[1], v[2]);
    if (d.allFinite() && d.norm() > 1e-6) return Vec3(d.normalized().cast<float>());
    return invalid_argument("bad up vector '" + original + "' (zero or not finite)");
  }
  return invalid_argument("bad up direction '" + original + "' (want +x, -x, +y, -y, +z, -z or a vector 'x y z')");
}

std::string up_to_string(const Vec3& up) {
  for (int a = 0; a < 3; ++a)
    for (float sign : {1.f, -1.f})
      if (up == sign * Vec3::Unit(a)) return std::string(sign > 0 ? "+" : "-") + char('x' + a);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3f %.3f %.3f", up.x(), up.y(), up.z());
  return buf;
}

Eigen::Matrix3f upright_rotation(const Vec3& up) {
  Eigen::Matrix3f r;
  // rows give the new x, y, z; each is a quarter or half turn about one axis
  if (up == Vec3(0, 0, 1)) r << 1, 0, 0, 0, 1, 0, 0, 0, 1;
  else if (up == Vec3(0, 0, -1)) r << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // half turn about x
  else if (up == Vec3(0, 1, 0)) r << 1, 0, 0, 0, 0, -1, 0, 1, 0;    // +90 deg about x
  else if (up == Vec3(0, -1, 0)) r << 1, 0, 0, 0, 0, 1, 0, -1, 0;   // -90 deg about x
  else if (up == Vec3(1, 0, 0)) r << 0, 0, -1, 0, 1, 0, 1, 0, 0;    // -90 deg about y
  else if (up == Vec3(-1, 0, 0)) r << 0, 0, 1, 0, 1, 0, -1, 0, 0;   // +90 deg about y
  else {
    const Eigen::Vector3d u = up.cast<double>().normalized();
    if (!u.allFinite()) return Eigen::Matrix3f::Identity();
    // FromTwoVectors picks some axis for the half turn of u = -z; that case is an axis above.
    r = Eigen::Quaterniond::FromTwoVectors(u, Eigen::Vector3d::UnitZ()).toRotationMatrix().cast<float>();
  }
  return r;
}

Mesh stand_upright(Mesh mesh, const Vec3& up) {
  const Eigen::Matrix3f r = upright_rotation(up);
  return transform_vertices(std::move(mesh), [&](const Vec3& v) -> Vec3 { return r * v; });
}

Eigen::Matrix3f random_rotation(uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double u1 = uniform01(rng), u2 = uniform01(rng), u3 = uniform01(rng);
  const double two_pi = 2 * kPi;
  // Shoemake, "Uniform random rotations", Graphics Gems III, 1992: a uniform unit quaternion.
  const Eigen::Quaterniond q(std::sqrt(u1) * std::cos(two_pi * u3), std::sqrt(1 - u1) * std::sin(two_pi * u2),
                             std::sqrt(1 - u1) * std::cos(two_pi * u2), std::sqrt(u1) * std::sin(two_pi * u3));
  return q.normalized().toRotationMatrix().cast<float>();
}

Eigen::Matrix3f random_tilt(uint64_t seed, float max_deg) {
  std::mt19937_64 rng(seed);
  const double u1 = uniform01(rng), u2 = uniform01(rng);
  const double cap = std::cos(std::clamp(double(max_deg), 0.0, 180.0) * kPi / 180.0);
  const double angle = std::acos(1 - u1 * (1 - cap));  // uniform over the cap's area
  const double azimuth = 2 * kPi * u2;
  const Eigen::Vector3d axis(std::cos(azimuth), std::sin(azimuth), 0);
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix().cast<float>();
}

Cloud rotate_about_centroid(const Cloud& cloud, const Eigen::Matrix3f& rotation) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (const Vec3& p : cloud.points)
    if (p.allFinite()) c += p.cast<double>(), ++n;
  const Vec3 centre = n ? Vec3((c / double(n)).cast<float>()) : Vec3::Zero();
  Cloud out;
  out.points.reserve(cloud.points.size());
  for (const Vec3& p : cloud.points) out.points.push_back(rotation * (p - centre) + centre);
  if (cloud.sensor) out.sensor = rotation * (*cloud.sensor - centre) + centre;
  return out;
}

Points rotate_points(const Points& points, const Eigen::Matrix3f& rotation) {
  Points out;
  out.reserve(points.size());
  for (const Vec3& p : points) out.push_back(rotation * p);
  return out;
}

Mesh scale_uniform(Mesh mesh, float factor) {
  return transform_vertices(std::move(mesh), [&](const Vec3& v) -> Vec3 { return v * factor; });
}

Mesh scale_to_height(Mesh mesh, float height_m) {
  const float h = bounds(mesh.vertices).extent().z();
  if (!(h > 0) || !std::isfinite(h)) return mesh;
  return scale_uniform(std::move(mesh), height_m / h);
}

Mesh scale_to_largest_extent(Mesh mesh, float extent_m) {
  const float e = bounds(mesh.vertices).extent().maxCoeff();
  if (!(e > 0) || !std::isfinite(e)) return mesh;
  return scale_uniform(std::move(mesh), extent_m / e);
}

Points place_on_ground(Points points) {
  const Bounds b = bounds(points);
  const Vec3 shift(-b.centre().x(), -b.centre().y(), -b.min.z());
  for (Vec3& p : points) p += shift;
  return points;
}

Mesh place_on_ground(Mesh mesh) {
  mesh.vertices = place_on_ground(std::move(mesh.vertices));
  return mesh;
}

namespace {

// Convex hull of `coords` (count x 3) with qhull; marks the input indices below `marked` that are
// hull vertices. False when qhull reports an error.
bool hull_vertices(std::vector<coordT>& coords, int count, const char* options, FILE* errfile,
                   std::vector<char>& is_vertex) {
  auto qh = std::make_unique<qhT>();
  qh_zero(qh.get(), errfile);
  std::string command = options;  // qh_new_qhull takes a non-const char*
  const int code = qh_new_qhull(qh.get(), 3, count, coords.data(), False, command.data(), nullptr, errfile);
  bool ok = code == 0;
  if (ok) {
    qhT* const qh_ptr = qh.get();
    for (vertexT* v = qh_ptr->vertex_list; v && v->next; v = v->next) {
      const int id = qh_pointid(qh_ptr, v->point);
      if (id >= 0 && id < int(is_vertex.size())) is_vertex[id] = 1;
    }
  }
  qh_freeqhull(qh.get(), !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh.get(), &curlong, &totlong);
  return ok;
}

}  // namespace

std::vector<uint32_t> hidden_point_removal_indices(const Points& points, const Vec3& camera,
                                                   double radius_factor) {
  std::vector<uint32_t> usable;
  std::vector<Eigen::Vector3d> rel;
  const Eigen::Vector3d c = camera.cast<double>();
  double max_d = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const Eigen::Vector3d p = points[i].cast<double>() - c;
    const double d = p.norm();
    if (!(d > 0) || !std::isfinite(d)) continue;
    usable.push_back(uint32_t(i));
    rel.push_back(p);
    max_d = std::max(max_d, d);
  }
  if (usable.size() < 4 || !camera.allFinite()) return usable;
  // Katz et al. 2007, eq. 2: spherical flip p' = p + 2 (R - |p|) p / |p|, R beyond every point.
  const double radius = std::max(radius_factor, 1.01) * max_d;
  std::vector<coordT> coords;
  coords.reserve(3 * (rel.size() + 1));
  for (const Eigen::Vector3d& p : rel) {
    const Eigen::Vector3d f = p * ((2 * radius - p.norm()) / p.norm());
    coords.insert(coords.end(), {f.x(), f.y(), f.z()});
  }
  coords.insert(coords.end(), {0.0, 0.0, 0.0});  // the camera, at the origin of the flip
  FILE* devnull = std::fopen("/dev/null", "w");
  FILE* errfile = devnull ? devnull : std::tmpfile();
  std::vector<char> is_vertex(rel.size(), 0);
  const int count = int(rel.size() + 1);
  bool ok = errfile && hull_vertices(coords, count, "qhull Qt", errfile, is_vertex);
  if (!ok && errfile) {  // precision trouble (e.g. all points coplanar with the camera): joggle
    std::fill(is_vertex.begin(), is_vertex.end(), 0);
    ok = hull_vertices(coords, count, "qhull QJ", errfile, is_vertex);
  }
  if (errfile) std::fclose(errfile);
  if (!ok) return usable;
  std::vector<uint32_t> visible;
  for (size_t k = 0; k < usable.size(); ++k)
    if (is_vertex[k]) visible.push_back(usable[k]);
  return visible;
}

Cloud hidden_point_removal(const Points& points, const Vec3& camera, double radius_factor) {
  Cloud view;
  view.sensor = camera;
  for (uint32_t i : hidden_point_removal_indices(points, camera, radius_factor))
    view.points.push_back(points[i]);
  return view;
}

std::vector<Vec3> paper_viewpoints(const Points& points, float elevation_deg) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (const Vec3& p : points)
    if (p.allFinite()) centroid += p.cast<double>(), ++n;
  if (n == 0) return {};
  centroid /= double(n);
  double radius = 0;
  for (const Vec3& p : points)
    if (p.allFinite()) radius = std::max(radius, (p.cast<double>() - centroid).norm());
  const double distance = 3.0 * radius;  // sec. 3.4: 6 viewpoints around the object
  const double elevation = double(elevation_deg) * kPi / 180.0;
  std::vector<Vec3> cameras;
  for (int k = 0; k < 6; ++k) {
    const double azimuth = k * 60.0 * kPi / 180.0;
    const Eigen::Vector3d dir(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    cameras.push_back((centroid + distance * dir).cast<float>());
  }
  return cameras;
}

uint64_t object_seed(uint64_t seed, std::string_view key) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a: std::hash differs between standard libraries
  for (char c : key) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (h + 1);  // splitmix64 of the pair
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

Points object_cloud(const Mesh& mesh, size_t points, uint64_t seed) {
  const double area = points ? surface_area(mesh) : 0.0;
  return area > 0 ? sample_surface(mesh, double(points) / area, seed).points : mesh_vertices(mesh).points;
}

Cloud object_view(const Points& full, size_t view, size_t views, bool any_pose, uint64_t pose_seed,
                  double hpr_radius_factor, float elevation_deg) {
  views = std::clamp<size_t>(views, 1, 6);
  const size_t viewpoint = (std::min(view, views - 1) * 6) / views;
  Points posed;
  if (any_pose) posed = place_on_ground(rotate_points(full, random_rotation(object_seed(pose_seed, std::to_string(view)))));
  const Points& cloud = any_pose ? posed : full;
  const std::vector<Vec3> cameras = paper_viewpoints(cloud, elevation_deg);
  if (viewpoint >= cameras.size()) return Cloud{};
  return hidden_point_removal(cloud, cameras[viewpoint], hpr_radius_factor);
}

namespace {
// Before in the top-down order: higher, non-NaN before NaN (stable: ties keep their order).
bool above(const Points& points, uint32_t a, uint32_t b) {
  const float za = points[a].z(), zb = points[b].z();
  if (std::isnan(za) || std::isnan(zb)) return !std::isnan(za) && std::isnan(zb);
  return za > zb;
}
}  // namespace

std::vector<uint32_t> top_down_order(const Points& points) {
  std::vector<uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return above(points, a, b); });
  return order;
}

std::vector<uint32_t> highest_points(const Points& points, size_t count) {
  std::vector<uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  count = std::min(count, order.size());
  // Ties broken by index, as the stable sort does: the same set.
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count), order.end(), [&](uint32_t a, uint32_t b) {
    return above(points, a, b) || (!above(points, b, a) && a < b);
  });
  order.resize(count);
  std::sort(order.begin(), order.end());
  return order;
}

Cloud reveal_top_down(const Cloud& cloud, size_t count) {
  const std::vector<uint32_t> order = top_down_order(cloud.points);
  Cloud out;
  out.sensor = cloud.sensor;
  count = std::min(count, order.size());
  out.points.reserve(count);
  for (size_t i = 0; i < count; ++i) out.points.push_back(cloud.points[order[i]]);
  return out;
}

}  // namespace glimpse
