#include "client/cloud_convert.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>

namespace glimpse::client {
namespace {

void PutFloat(float f, char* out) {
  const uint32_t u = std::bit_cast<uint32_t>(f);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<char>((u >> (8 * i)) & 0xff);
}

float GetFloat(const char* in) {
  uint32_t u = 0;
  for (int i = 0; i < 4; ++i) u |= static_cast<uint32_t>(static_cast<unsigned char>(in[i])) << (8 * i);
  return std::bit_cast<float>(u);
}

}  // namespace

void ToProto(const Cloud& cloud, size_t begin, size_t end, v1::PointCloud* out) {
  end = std::min(end, cloud.points.size());
  begin = std::min(begin, end);
  std::string* xyz = out->mutable_xyz();
  xyz->resize((end - begin) * 12);
  char* p = xyz->data();
  for (size_t i = begin; i < end; ++i, p += 12)
    for (int k = 0; k < 3; ++k) PutFloat(cloud.points[i][k], p + 4 * k);
  out->clear_normals();
  if (cloud.sensor) {
    out->mutable_sensor()->set_x(cloud.sensor->x());
    out->mutable_sensor()->set_y(cloud.sensor->y());
    out->mutable_sensor()->set_z(cloud.sensor->z());
  } else {
    out->clear_sensor();
  }
}

void ToProto(const Cloud& cloud, v1::PointCloud* out) { ToProto(cloud, 0, cloud.points.size(), out); }

v1::PointCloud ToProto(const Cloud& cloud) {
  v1::PointCloud out;
  ToProto(cloud, &out);
  return out;
}

Expected<Cloud> FromProto(const v1::PointCloud& proto) {
  const std::string& xyz = proto.xyz();
  if (xyz.size() % 12 != 0)
    return invalid_argument("xyz has " + std::to_string(xyz.size()) + " bytes, not a multiple of 12");
  Cloud cloud;
  cloud.points.resize(xyz.size() / 12);
  const char* p = xyz.data();
  for (Vec3& v : cloud.points) {
    v = Vec3(GetFloat(p), GetFloat(p + 4), GetFloat(p + 8));
    p += 12;
  }
  if (proto.has_sensor()) cloud.sensor = Vec3(proto.sensor().x(), proto.sensor().y(), proto.sensor().z());
  return cloud;
}

size_t RemoveNonFinite(Cloud& cloud) {
  const size_t before = cloud.points.size();
  std::erase_if(cloud.points, [](const Vec3& v) { return !v.allFinite(); });
  return before - cloud.points.size();
}

}  // namespace glimpse::client
