#include "client/parse.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

namespace glimpse::client {
namespace {

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool ValidName(std::string_view name) {
  if (name.empty() || name.size() > 128) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
}

struct MethodEntry {
  const char* name;
  v1::Method method;
};
constexpr MethodEntry kMethods[] = {{"bok", v1::METHOD_BOK}, {"bog", v1::METHOD_BOG}, {"kgh", v1::METHOD_KGH},
                                    {"vfh", v1::METHOD_VFH}, {"esf", v1::METHOD_ESF}, {"ush", v1::METHOD_USH},
                                    {"size", v1::METHOD_SIZE},   {"fusion", v1::METHOD_FUSION}};

}  // namespace

Expected<v1::ModelRef> ParseModelRef(std::string_view text, bool allow_latest) {
  v1::ModelRef ref;
  std::string_view name = text, version;
  if (auto colon = text.find(':'); colon != std::string_view::npos) {
    name = text.substr(0, colon);
    version = text.substr(colon + 1);
  }
  if (!ValidName(name))
    return invalid_argument("bad model name '" + std::string(name) + "': 1-128 characters from [A-Za-z0-9._-]");
  ref.set_name(std::string(name));
  if (version.data() == nullptr) return ref;
  if (version == "latest") {
    if (allow_latest) return ref;
    return invalid_argument("'" + std::string(text) + "': 'latest' is for models set-default only; NAME alone is its " +
                            "default version (the newest unless one is pinned), NAME:N a version");
  }
  uint32_t v = 0;
  auto [end, ec] = std::from_chars(version.data(), version.data() + version.size(), v);
  if (ec != std::errc() || end != version.data() + version.size() || v == 0)
    return invalid_argument("bad model version '" + std::string(version) + "' in '" + std::string(text) +
                            "': a positive integer");
  ref.set_version(v);
  return ref;
}

Expected<Vec3> ParseSensor(std::string_view text) {
  const std::string bad = "bad sensor '" + std::string(text) + "': three finite numbers X,Y,Z in the cloud's own frame and unit";
  Vec3 out;
  std::string_view rest = text;
  for (int axis = 0; axis < 3; ++axis) {
    const size_t comma = rest.find(',');
    if ((axis < 2) == (comma == std::string_view::npos)) return invalid_argument(bad);
    const std::string_view item = Trim(rest.substr(0, comma));
    double v = 0;
    auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size() || !std::isfinite(v) ||
        std::abs(v) > 1e6)
      return invalid_argument(bad);
    out[axis] = static_cast<float>(v);
    if (axis < 2) rest = rest.substr(comma + 1);
  }
  return out;
}

std::string FormatModelRef(const v1::ModelRef& ref) {
  return ref.version() == 0 ? ref.name() : ref.name() + ":" + std::to_string(ref.version());
}

Expected<v1::Method> ParseMethod(std::string_view name) {
  const std::string lower = Lower(Trim(name));
  for (const MethodEntry& m : kMethods)
    if (lower == m.name) return m.method;
  std::string valid;
  for (const MethodEntry& m : kMethods) valid += (valid.empty() ? "" : ", ") + std::string(m.name);
  return invalid_argument("unknown method '" + std::string(Trim(name)) + "' (valid: " + valid + ")");
}

Expected<std::vector<v1::Method>> ParseMethodList(std::string_view text) {
  std::vector<v1::Method> methods;
  if (Trim(text).empty()) return methods;
  while (true) {
    const size_t comma = text.find(',');
    auto m = ParseMethod(text.substr(0, comma));
    if (!m) return m.error();
    if (std::find(methods.begin(), methods.end(), *m) != methods.end())
      return invalid_argument("method '" + MethodName(*m) + "' given twice");
    methods.push_back(*m);
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return methods;
}

std::string MethodName(v1::Method method) {
  for (const MethodEntry& m : kMethods)
    if (m.method == method) return m.name;
  return method == v1::METHOD_UNSPECIFIED ? "default" : "method" + std::to_string(static_cast<int>(method));
}

std::vector<std::string> MethodNames() {
  std::vector<std::string> names;
  for (const MethodEntry& m : kMethods) names.emplace_back(m.name);
  return names;
}

const char* StatusCodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    default: return "UNKNOWN";
  }
}

grpc::StatusCode StatusCodeOf(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument: return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorCode::kNotFound: return grpc::StatusCode::NOT_FOUND;
    case ErrorCode::kResourceExhausted: return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case ErrorCode::kFailedPrecondition: return grpc::StatusCode::FAILED_PRECONDITION;
    case ErrorCode::kDataLoss: return grpc::StatusCode::DATA_LOSS;
    case ErrorCode::kCancelled: return grpc::StatusCode::CANCELLED;
    case ErrorCode::kInternal: return grpc::StatusCode::INTERNAL;
  }
  return grpc::StatusCode::UNKNOWN;
}

}  // namespace glimpse::client
