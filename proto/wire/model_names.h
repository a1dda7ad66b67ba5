// Model names as the contract has them: 1-128 characters from [A-Za-z0-9._-] (glimpse.proto, ModelRef).
#pragma once

#include <cstddef>
#include <string_view>

#include "glimpse/expected.h"

namespace glimpse::wire {

inline constexpr size_t kMaxModelNameLength = 128;

// INVALID_ARGUMENT saying what is wrong: empty, too long, or a character outside the alphabet.
Status ValidateModelName(std::string_view name);

}  // namespace glimpse::wire
