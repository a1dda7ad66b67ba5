// Hidden point removal (Katz, Tal & Basri 2007) and the paper's six viewpoints (sec. 3.4).
#include "glimpse/views/hidden_point_removal.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "glimpse/views/placement.h"
#include "glimpse/views/sampling.h"

namespace glimpse {

namespace {

constexpr double kPi = 3.14159265358979323846;

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

}  // namespace glimpse
