// The recognition methods and what each is made of: the paper's keypoint methods (BoK, BoG, KGH), its VFH
// baseline, ESF, our upright shape histogram, the size-only baseline and the score-level fusion.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string_view>
#include <vector>

#include "glimpse/expected.h"

namespace glimpse {

// The recognition methods of the paper (BoK, BoG, KGH, VFH), ESF, our upright shape histogram (USH,
// upright_histogram.h), a size-only baseline (the visible height and horizontal extents: how much a
// ruler alone gets right) and a score-level fusion. The numbers are stored in model bytes: never
// reuse one.
enum class MethodId : uint8_t { kBoK = 0, kBoG = 1, kKGH = 2, kVFH = 3, kESF = 4, kFusion = 5, kUSH = 6, kSize = 7 };
inline constexpr int kMethodCount = 8;
inline constexpr MethodId kAllMethods[] = {MethodId::kBoK, MethodId::kBoG, MethodId::kKGH,  MethodId::kVFH,
                                         MethodId::kESF, MethodId::kUSH, MethodId::kSize, MethodId::kFusion};
// What a model learns when nobody names its methods (TrainParams, a Train request without methods): the
// fusion (the default method), its components and the size-only baseline. The paper's keypoint methods
// and ESF are learnt when asked for: their features take about 5 times as long to compute (SHREC with the
// zoo on 2 cores: 424 s of training against 83 s).
inline constexpr MethodId kDefaultMethods[] = {MethodId::kVFH, MethodId::kUSH, MethodId::kSize, MethodId::kFusion};
const char* method_name(MethodId m);  // "bok", "bog", "kgh", "vfh", "esf", "ush", "size", "fusion"
Expected<MethodId> parse_method(std::string_view name);   // case-insensitive; error lists valid names

// The paper's keypoint methods (sec. 3.2.5-3.2.7): they read the keypoints and their descriptors.
inline bool uses_keypoints(MethodId m) { return m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH; }
// Whether `methods` lists m.
inline bool needs(const std::vector<MethodId>& methods, MethodId m) {
  return std::find(methods.begin(), methods.end(), m) != methods.end();
}

}  // namespace glimpse
