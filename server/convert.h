// Messages <-> core types, with the validation a request needs before it reaches core. Every function
// here is pure (no I/O, no gRPC calls) so it can be unit-tested and fuzzed on its own.
#pragma once

#include <grpcpp/support/status.h>

#include <optional>
#include <string_view>

#include "engine.h"
#include "glimpse/v1/glimpse.pb.h"
#include "store.h"

namespace glimpse::server {

// Unpacks xyz (little-endian float32 triples), the sensor and normals. INVALID_ARGUMENT for a byte
// length that is not a multiple of 12, normals that do not match xyz, or a NaN/Inf value or a
// coordinate beyond +-1e6 m (naming the first bad point's index); RESOURCE_EXHAUSTED above max_points.
Expected<Cloud> CloudFromProto(const v1::PointCloud& msg, size_t max_points);
// The inverse, for clients and tests.
v1::PointCloud CloudToProto(const Cloud& cloud);
std::string PackPoints(const Points& points);

// METHOD_UNSPECIFIED -> nullopt (the model's default); values outside the enum -> INVALID_ARGUMENT.
Expected<std::optional<MethodId>> MethodFromProto(int method);
v1::Method MethodToProto(MethodId method);

// A request's operating point of "unknown": 0 (the model's default) or a share in (0, 1];
// INVALID_ARGUMENT otherwise (NaN included).
Expected<double> KnownAcceptanceFromProto(double known_acceptance);

// Names are 1-128 characters from [A-Za-z0-9._-].
Status ValidateModelName(std::string_view name);
// Checks a Train header: name, methods, parameter ranges, description length.
Expected<TrainSpec> TrainSpecFromProto(const v1::TrainHeader& header);

void ToProto(const ModelRecord& record, v1::ModelInfo* out);
void ToProto(const Classification& c, v1::ClassifyResponse* out);
void ToProto(const StreamDecision& d, v1::Decision* out);

// The one mapping from core errors to gRPC status codes. kCancelled becomes DEADLINE_EXCEEDED when
// the deadline, not the caller, stopped the work.
grpc::Status ToGrpcStatus(const Error& error, bool deadline_exceeded = false);

}  // namespace glimpse::server
