#include "scene.h"

#include <cmath>
#include <string>

#include "batch.h"

namespace glimpse::server {
namespace {

v1::Vec3 Vec(const Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x()), out.set_y(v.y()), out.set_z(v.z());
  return out;
}

// Sets `target` to `value` when the field is set and within range; INVALID_ARGUMENT naming it otherwise.
template <class T, class V>
Status Take(bool has, const char* field, V value, double lo, double hi, bool lo_open, T& target) {
  if (!has) return {};
  const double v = static_cast<double>(value);
  if (!(std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi))
    return invalid_argument(std::string("scene.") + field + " is " + std::to_string(v) + "; it must be in " +
                            (lo_open ? "(" : "[") + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  target = static_cast<T>(value);
  return {};
}

}  // namespace

Expected<SceneParams> SceneParamsFromProto(const v1::SceneParameters& in) {
  SceneParams p;
  for (const Status& s : {
           Take(in.has_voxel_m(), "voxel_m", in.voxel_m(), 0, 0.2, false, p.voxel_m),
           Take(in.has_cluster_tolerance_m(), "cluster_tolerance_m", in.cluster_tolerance_m(), 0, 1, true,
                p.cluster_tolerance_m),
           Take(in.has_min_object_points(), "min_object_points", in.min_object_points(), 1, 1e6, false,
                p.min_object_points),
           Take(in.has_max_object_extent_m(), "max_object_extent_m", in.max_object_extent_m(), 0, 50, true,
                p.max_object_extent_m),
           Take(in.has_max_objects(), "max_objects", in.max_objects(), 1, 256, false, p.max_objects),
           Take(in.has_min_plane_area_m2(), "min_plane_area_m2", in.min_plane_area_m2(), 0, 100, false,
                p.min_plane_area_m2),
           Take(in.has_reference_density_per_deg2(), "reference_density_per_deg2", in.reference_density_per_deg2(), 0,
                1e6, false, p.reference_density_per_deg2)})
    if (!s.ok()) return s.error();
  return p;
}

Expected<TrackTarget> TrackTargetFromProto(const v1::TrackTarget& in) {
  TrackTarget t;
  switch (in.target_case()) {
    case v1::TrackTarget::kNearestAxis:
      if (!in.nearest_axis()) break;
      t.kind = TrackTarget::Kind::kNearestAxis;
      return t;
    case v1::TrackTarget::kPoint:
      t.kind = TrackTarget::Kind::kPoint;
      t.point = Vec3(in.point().x(), in.point().y(), in.point().z());
      return t;
    case v1::TrackTarget::kBox:
      t.kind = TrackTarget::Kind::kBox;
      t.box_min = Vec3(in.box().min().x(), in.box().min().y(), in.box().min().z());
      t.box_max = Vec3(in.box().max().x(), in.box().max().y(), in.box().max().z());
      return t;
    case v1::TrackTarget::TARGET_NOT_SET:
      break;
  }
  return invalid_argument("track names no target: set nearest_axis (true), point or box");
}

void ToProto(const SceneObject& object, bool indices, v1::SceneObject* out) {
  *out->mutable_box_min() = Vec(object.box_min);
  *out->mutable_box_max() = Vec(object.box_max);
  *out->mutable_centroid() = Vec(object.centroid);
  out->set_range_m(object.range_m);
  out->set_points(object.points.size());
  if (indices) out->mutable_indices()->Add(object.indices.begin(), object.indices.end());
}

std::string SceneWarning(const Scene& scene) {
  if (scene.planes.empty() || has_level_plane(scene)) return {};
  return "no plane removed from the frame is a floor or a table top (level, below the sensor): is +z up? "
         "A camera's own coordinates (y down, z forward) need levelling first (glimpse scene --up floor); the "
         "categories of a frame on its side are not to be trusted";
}

void FillSceneResponse(const Scene& scene, const std::vector<Expected<Classification>>& results,
                       const ModelRecord& model, double model_load_ms, bool indices, v1::ClassifySceneResponse* out) {
  for (const Plane& plane : scene.planes) {
    v1::ScenePlane* p = out->add_planes();
    *p->mutable_normal() = Vec(plane.normal);
    p->set_offset(plane.offset);
    p->set_points(plane.inliers);
  }
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    v1::SceneObject* o = out->add_objects();
    ToProto(scene.objects[i], indices, o);
    const Expected<Classification>& c = results[i];
    if (c) SetResult(*c, model, model_load_ms, o->mutable_result());
    else SetError(Error{c.error().code, "object " + std::to_string(i) + ": " + c.error().message}, o->mutable_result());
  }
  out->set_frame_points(scene.finite_points);
  out->set_warning(SceneWarning(scene));
}

}  // namespace glimpse::server
