// Small parsers and names shared by the commands: model references ("chair:3"), method names
// ("bok,bog"), gRPC status code names. Pure functions, no I/O.
#pragma once

#include <grpcpp/support/status.h>

#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::client {

// "NAME" or "NAME:VERSION" (VERSION a positive integer; NAME alone is version 0, the name's default).
// Names are 1-128 characters from [A-Za-z0-9._-], as in the proto.
// "latest" (version 0: unpinned, the newest) only where `allow_latest` (models set-default): elsewhere
// version 0 asks for the name's default, which may be pinned, and deleting it would delete every version.
Expected<v1::ModelRef> ParseModelRef(std::string_view text, bool allow_latest = false);
// "name:3", or just "name" for version 0.
std::string FormatModelRef(const v1::ModelRef& ref);

// "bok", "bog", "kgh", "vfh", "esf", "ush", "fusion" (case-insensitive).
Expected<v1::Method> ParseMethod(std::string_view name);
// Comma-separated, e.g. "bok,bog"; blanks around names ignored; no duplicates; empty text -> empty list.
Expected<std::vector<v1::Method>> ParseMethodList(std::string_view text);
// "bok" ... "fusion"; "default" for METHOD_UNSPECIFIED.
std::string MethodName(v1::Method method);
std::vector<std::string> MethodNames();  // the names ParseMethod accepts, in enum order

// A sensor position "X,Y,Z" in the cloud's frame (metres, finite), e.g. "0,0,0" for a camera-frame
// scan whose file does not say where the camera was.
Expected<Vec3> ParseSensor(std::string_view text);

// "NOT_FOUND", "DEADLINE_EXCEEDED", ... as in grpc/status.h and every other gRPC client.
const char* StatusCodeName(grpc::StatusCode code);
// The gRPC code a core error would have over the wire (a missing file is NOT_FOUND, ...), so a local
// failure reads like a server's.
grpc::StatusCode StatusCodeOf(ErrorCode code);

}  // namespace glimpse::client
