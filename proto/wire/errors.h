// Core errors as gRPC statuses, and the names of gRPC status codes: the one mapping the server answers
// with and the client reports its own failures in, so a local failure reads like a server's.
#pragma once

#include <grpcpp/support/status.h>

#include "glimpse/expected.h"

namespace glimpse::wire {

// The gRPC code of a core error (a missing file or model is NOT_FOUND, ...).
grpc::StatusCode ToGrpcCode(ErrorCode code);
// The error as a status with its message. kCancelled becomes DEADLINE_EXCEEDED when the deadline, not the
// caller, stopped the work.
grpc::Status ToGrpcStatus(const Error& error, bool deadline_exceeded = false);

// "NOT_FOUND", "DEADLINE_EXCEEDED", ... as in grpc/status.h and every other gRPC client; "UNKNOWN" for a
// code outside the list.
const char* StatusCodeName(grpc::StatusCode code);

}  // namespace glimpse::wire
