// The recognition methods on the wire: v1::Method <-> core's MethodId, and their names as core gives them
// ("bok", "bog", ..., "fusion"), for requests, replies, logs and the command line.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/features/methods.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::wire {

// METHOD_UNSPECIFIED -> nullopt (the model's default); values outside the enum -> INVALID_ARGUMENT.
Expected<std::optional<MethodId>> MethodFromProto(int method);
v1::Method MethodToProto(MethodId method);

// "bok" ... "fusion"; "default" for METHOD_UNSPECIFIED (or no method); "method<N>" outside the enum.
std::string MethodName(v1::Method method);
std::string MethodName(std::optional<MethodId> method);
// The names ParseMethod accepts, in core's kAllMethods order.
std::vector<std::string> MethodNames();
// A method by name: case-insensitive, blanks around it ignored; the error lists the valid names.
Expected<v1::Method> ParseMethod(std::string_view name);

}  // namespace glimpse::wire
