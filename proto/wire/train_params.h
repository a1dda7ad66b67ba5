// Training parameters on the wire: a Train header checked into a TrainSpec, mapped onto core's
// TrainParams (unset fields keep core's defaults) and back (every field set: what training used).
#pragma once

#include <optional>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::wire {

inline constexpr size_t kMaxDescriptionBytes = 4096;

// What a Train header asks for, before it is mapped onto core's TrainParams.
struct TrainSpec {
  std::vector<MethodId> methods;  // empty: core's kDefaultMethods
  std::optional<MethodId> default_method;
  v1::TrainParameters parameters;
};

// Checks a Train header: name, description length, methods, parameter ranges (INVALID_ARGUMENT).
Expected<TrainSpec> TrainSpecFromProto(const v1::TrainHeader& header);
// The spec on core's TrainParams; INVALID_ARGUMENT for a count beyond int.
Expected<TrainParams> ToTrainParams(const TrainSpec& spec);
// Every field of TrainParameters from core's TrainParams (the inverse of ToTrainParams).
v1::TrainParameters FromTrainParams(const TrainParams& params);

}  // namespace glimpse::wire
