#include "proto/wire/clouds.h"

#include <algorithm>
#include <bit>
#include <cstdint>

namespace glimpse::wire {
namespace {

void WriteFloatLE(float f, char* out) {
  const uint32_t u = std::bit_cast<uint32_t>(f);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<char>((u >> (8 * i)) & 0xff);
}

float ReadFloatLE(const char* in) {
  uint32_t u = 0;
  for (int i = 0; i < 4; ++i) u |= static_cast<uint32_t>(static_cast<unsigned char>(in[i])) << (8 * i);
  return std::bit_cast<float>(u);
}

void PackInto(const Vec3* begin, const Vec3* end, std::string* out) {
  out->resize(static_cast<size_t>(end - begin) * kBytesPerPoint);
  char* p = out->data();
  for (const Vec3* v = begin; v != end; ++v, p += kBytesPerPoint)
    for (int k = 0; k < 3; ++k) WriteFloatLE((*v)[k], p + 4 * k);
}

// The first point that is not finite or lies beyond +-1e6 m, named by its index.
Status CheckPoints(const Points& points, std::string_view what) {
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      return invalid_argument(std::string(what) + ": point " + std::to_string(i) + " is not finite");
    if (points[i].cwiseAbs().maxCoeff() > kMaxAbsCoordinateM)
      return invalid_argument(std::string(what) + ": point " + std::to_string(i) +
                              " has a coordinate beyond +-1e6 m (clouds are in metres)");
  }
  return {};
}

Status CheckNormals(const v1::PointCloud& msg) {
  if (msg.normals().empty()) return {};
  if (msg.normals().size() != msg.xyz().size())
    return invalid_argument("normals has " + std::to_string(msg.normals().size()) + " bytes; xyz has " +
                            std::to_string(msg.xyz().size()) + " and they must match");
  auto normals = UnpackPoints(msg.normals(), "normals");
  if (!normals) return normals.error();
  return CheckPoints(*normals, "normals");
}

Status CheckSensor(const Vec3& sensor) {
  if (!sensor.allFinite()) return invalid_argument("sensor position is not finite");
  if (sensor.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM)
    return invalid_argument("sensor position has a coordinate beyond +-1e6 m (clouds are in metres)");
  return {};
}

// A frame the image's edges can be found from: a sensor to see from, finite directions, the up not
// along the axis, fields of view in (0, 180) degrees.
Status CheckFrame(const CameraFrame& f, bool has_sensor) {
  if (!has_sensor) return invalid_argument("frame needs the sensor position it is seen from (sensor is unset)");
  if (!f.axis.allFinite() || !(f.axis.norm() > 0)) return invalid_argument("frame.axis must be a finite, non-zero direction");
  if (!f.up.allFinite() || !(f.axis.normalized().cross(f.up).norm() > 1e-3f))
    return invalid_argument("frame.image_up must be a finite direction not along frame.axis");
  auto fov_ok = [](float deg) { return deg > 0 && deg < 180; };
  if (!fov_ok(f.fov_h_deg) || !fov_ok(f.fov_v_deg))
    return invalid_argument("frame fields of view must be in (0, 180) degrees, not " + std::to_string(f.fov_h_deg) +
                            " x " + std::to_string(f.fov_v_deg));
  return {};
}

}  // namespace

std::string PackPoints(const Points& points) {
  std::string out;
  PackInto(points.data(), points.data() + points.size(), &out);
  return out;
}

Expected<Points> UnpackPoints(std::string_view bytes, std::string_view what) {
  if (bytes.size() % kBytesPerPoint != 0)
    return invalid_argument(std::string(what) + " has " + std::to_string(bytes.size()) +
                            " bytes; it must be a multiple of 12 (packed little-endian float32 x, y, z)");
  Points points(bytes.size() / kBytesPerPoint);
  const char* p = bytes.data();
  for (Vec3& v : points) {
    v = Vec3(ReadFloatLE(p), ReadFloatLE(p + 4), ReadFloatLE(p + 8));
    p += kBytesPerPoint;
  }
  return points;
}

void CloudToProto(const Cloud& cloud, size_t begin, size_t end, v1::PointCloud* out) {
  end = std::min(end, cloud.points.size());
  begin = std::min(begin, end);
  PackInto(cloud.points.data() + begin, cloud.points.data() + end, out->mutable_xyz());
  out->clear_normals();
  if (cloud.sensor) {
    out->mutable_sensor()->set_x(cloud.sensor->x());
    out->mutable_sensor()->set_y(cloud.sensor->y());
    out->mutable_sensor()->set_z(cloud.sensor->z());
  } else {
    out->clear_sensor();
  }
  if (cloud.frame) {
    v1::CameraFrame* f = out->mutable_frame();
    auto set = [](v1::Vec3* v, const Vec3& from) { v->set_x(from.x()), v->set_y(from.y()), v->set_z(from.z()); };
    set(f->mutable_axis(), cloud.frame->axis);
    set(f->mutable_image_up(), cloud.frame->up);
    f->set_fov_h_deg(cloud.frame->fov_h_deg);
    f->set_fov_v_deg(cloud.frame->fov_v_deg);
  } else {
    out->clear_frame();
  }
}

void CloudToProto(const Cloud& cloud, v1::PointCloud* out) { CloudToProto(cloud, 0, cloud.points.size(), out); }

v1::PointCloud CloudToProto(const Cloud& cloud) {
  v1::PointCloud out;
  CloudToProto(cloud, &out);
  return out;
}

Expected<Cloud> DecodeCloud(const v1::PointCloud& msg) {
  auto points = UnpackPoints(msg.xyz(), "xyz");
  if (!points) return points.error();
  Cloud cloud;
  cloud.points = std::move(*points);
  if (msg.has_sensor()) cloud.sensor = Vec3(msg.sensor().x(), msg.sensor().y(), msg.sensor().z());
  if (msg.has_frame()) {
    const v1::CameraFrame& f = msg.frame();
    cloud.frame = CameraFrame{Vec3(f.axis().x(), f.axis().y(), f.axis().z()),
                              Vec3(f.image_up().x(), f.image_up().y(), f.image_up().z()), f.fov_h_deg(), f.fov_v_deg()};
  }
  return cloud;
}

Expected<Cloud> CloudFromProto(const v1::PointCloud& msg, size_t max_points) {
  const size_t n = msg.xyz().size() / kBytesPerPoint;
  if (n > max_points)
    return resource_exhausted("cloud has " + std::to_string(n) + " points; the limit is " + std::to_string(max_points));
  auto cloud = DecodeCloud(msg);
  if (!cloud) return cloud.error();
  if (Status s = CheckPoints(cloud->points, "xyz"); !s.ok()) return s.error();
  if (Status s = CheckNormals(msg); !s.ok()) return s.error();
  if (cloud->sensor)
    if (Status s = CheckSensor(*cloud->sensor); !s.ok()) return s.error();
  if (cloud->frame)
    if (Status s = CheckFrame(*cloud->frame, cloud->sensor.has_value()); !s.ok()) return s.error();
  return cloud;
}

}  // namespace glimpse::wire
