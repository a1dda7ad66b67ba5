#include "proto/wire/model_names.h"

#include <string>

namespace glimpse::wire {

Status ValidateModelName(std::string_view name) {
  if (name.empty()) return invalid_argument("model name is empty");
  if (name.size() > kMaxModelNameLength)
    return invalid_argument("model name is longer than " + std::to_string(kMaxModelNameLength) + " characters");
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) return invalid_argument("model name may only contain A-Z a-z 0-9 . _ -");
  }
  return {};
}

}  // namespace glimpse::wire
