#include "proto/wire/methods.h"

#include <cctype>
#include <iterator>

namespace glimpse::wire {
namespace {

struct MethodPair {
  MethodId id;
  v1::Method proto;
};
// Every method once, in kAllMethods order: the one table between the two enums.
constexpr MethodPair kMethods[] = {{MethodId::kBoK, v1::METHOD_BOK},   {MethodId::kBoG, v1::METHOD_BOG},
                                   {MethodId::kKGH, v1::METHOD_KGH},   {MethodId::kVFH, v1::METHOD_VFH},
                                   {MethodId::kESF, v1::METHOD_ESF},   {MethodId::kUSH, v1::METHOD_USH},
                                   {MethodId::kSize, v1::METHOD_SIZE}, {MethodId::kFusion, v1::METHOD_FUSION}};
static_assert(std::size(kMethods) == kMethodCount);

// "METHOD_BOK, METHOD_BOG, ...": the enum's values in number order.
std::string ProtoNames() {
  std::string out;
  for (int v = v1::Method_MIN; v <= v1::Method_MAX; ++v)
    if (v != v1::METHOD_UNSPECIFIED && v1::Method_IsValid(v))
      out += (out.empty() ? "" : ", ") + v1::Method_Name(static_cast<v1::Method>(v));
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

}  // namespace

Expected<std::optional<MethodId>> MethodFromProto(int method) {
  if (method == v1::METHOD_UNSPECIFIED) return std::optional<MethodId>();
  for (const MethodPair& m : kMethods)
    if (m.proto == method) return std::optional<MethodId>(m.id);
  return invalid_argument("unknown method " + std::to_string(method) + "; valid: " + ProtoNames());
}

v1::Method MethodToProto(MethodId method) {
  for (const MethodPair& m : kMethods)
    if (m.id == method) return m.proto;
  return v1::METHOD_UNSPECIFIED;
}

std::string MethodName(v1::Method method) {
  auto id = MethodFromProto(method);
  if (!id) return "method" + std::to_string(static_cast<int>(method));
  return MethodName(*id);
}

std::string MethodName(std::optional<MethodId> method) { return method ? method_name(*method) : "default"; }

std::vector<std::string> MethodNames() {
  std::vector<std::string> names;
  for (MethodId m : kAllMethods) names.emplace_back(method_name(m));
  return names;
}

Expected<v1::Method> ParseMethod(std::string_view name) {
  auto id = parse_method(Trim(name));
  if (!id) return id.error();
  return MethodToProto(*id);
}

}  // namespace glimpse::wire
