// Orientation, size and placement of objects and scans.
#include "glimpse/views/placement.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <locale>
#include <random>
#include <sstream>
#include <string>

#include "glimpse/random.h"

namespace glimpse {

namespace {

constexpr double kPi = 3.14159265358979323846;

template <class F>
Mesh transform_vertices(Mesh mesh, F&& f) {
  for (Vec3& v : mesh.vertices) v = f(v);
  return mesh;
}

}  // namespace

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
  if (cloud.frame) {  // the camera turns with what it saw
    out.frame = cloud.frame;
    out.frame->axis = rotation * cloud.frame->axis;
    out.frame->up = rotation * cloud.frame->up;
  }
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

}  // namespace glimpse
