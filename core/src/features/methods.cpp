// The methods by name.
#include "glimpse/features/methods.h"

#include <cctype>
#include <string>

namespace glimpse {

const char* method_name(MethodId m) {
  switch (m) {
    case MethodId::kBoK: return "bok";
    case MethodId::kBoG: return "bog";
    case MethodId::kKGH: return "kgh";
    case MethodId::kVFH: return "vfh";
    case MethodId::kESF: return "esf";
    case MethodId::kUSH: return "ush";
    case MethodId::kSize: return "size";
    case MethodId::kFusion: return "fusion";
  }
  return "unknown";
}

Expected<MethodId> parse_method(std::string_view name) {
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (MethodId m : kAllMethods)
    if (lower == method_name(m)) return m;
  return invalid_argument("unknown method '" + std::string(name) + "' (valid: bok, bog, kgh, vfh, esf, ush, size, fusion)");
}

}  // namespace glimpse
