// glimpse::Cloud <-> glimpse.v1.PointCloud. The wire layout: xyz (and normals) as packed little-endian
// float32 triples, on any host byte order. A cloud decodes as it is (DecodeCloud) or with the checks a
// request needs before it reaches core (CloudFromProto).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::wire {

inline constexpr size_t kBytesPerPoint = 12;  // x, y, z as float32
// Clouds are in metres; beyond 1000 km float32 has no centimetres left, and core's voxel keys and kd-tree
// splits overflow near float's range (PCL's kd-tree asserts on a cloud at 3e38 m).
inline constexpr float kMaxAbsCoordinateM = 1e6f;

// The points as packed triples.
std::string PackPoints(const Points& points);
// The packed triples of `bytes`; INVALID_ARGUMENT naming `what` for a length not a multiple of 12.
Expected<Points> UnpackPoints(std::string_view bytes, std::string_view what);

// Packs points[begin, end) (clamped to the cloud) with the cloud's sensor, every point as given: one
// chunk of a scan. The whole message is replaced (a reused one loses an old sensor and normals).
void CloudToProto(const Cloud& cloud, size_t begin, size_t end, v1::PointCloud* out);
void CloudToProto(const Cloud& cloud, v1::PointCloud* out);
v1::PointCloud CloudToProto(const Cloud& cloud);

// The points and the sensor as they are (normals ignored); INVALID_ARGUMENT only for an xyz length that
// is not a multiple of 12.
Expected<Cloud> DecodeCloud(const v1::PointCloud& msg);
// A request's cloud: RESOURCE_EXHAUSTED above max_points; INVALID_ARGUMENT for a byte length that is
// not a multiple of 12, normals that do not match xyz, or a NaN/Inf value or a coordinate beyond
// +-1e6 m (naming the first bad point's index). Normals are checked, not kept: core estimates its own.
Expected<Cloud> CloudFromProto(const v1::PointCloud& msg, size_t max_points);

}  // namespace glimpse::wire
