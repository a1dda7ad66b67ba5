// glimpse::Cloud <-> glimpse.v1.PointCloud: xyz (and the sensor) as packed little-endian float32
// triples, the wire layout of the proto, on any host byte order.
#pragma once

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::client {

// Packs every point as given (the server refuses non-finite values: see RemoveNonFinite).
void ToProto(const Cloud& cloud, v1::PointCloud* out);
v1::PointCloud ToProto(const Cloud& cloud);

// Packs points[begin, end) only, with the cloud's sensor: one chunk of a scan.
void ToProto(const Cloud& cloud, size_t begin, size_t end, v1::PointCloud* out);

// kInvalidArgument when xyz is not a whole number of 12-byte points. Normals are ignored.
Expected<Cloud> FromProto(const v1::PointCloud& proto);

// Drops points with a NaN or infinite coordinate (PCD files keep NaN points); returns how many.
size_t RemoveNonFinite(Cloud& cloud);

}  // namespace glimpse::client
