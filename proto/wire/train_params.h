// Training parameters on the wire: a Train header checked into a TrainSpec, mapped onto core's
// TrainParams (unset fields keep core's defaults) and back (every field set: what training used).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::wire {

inline constexpr size_t kMaxDescriptionBytes = 4096;

// A stored version a Train call grows (TrainHeader.base); version 0: the name's default.
struct BaseRef {
  std::string name;
  uint32_t version = 0;
};

// What a Train header asks for, before it is mapped onto core's TrainParams.
struct TrainSpec {
  std::vector<MethodId> methods;  // empty: core's kDefaultMethods
  std::optional<MethodId> default_method;
  v1::TrainParameters parameters;
  std::optional<BaseRef> base;  // set: methods and parameters are the base's
};

// Checks a Train header: name, description length, methods, parameter ranges, a base with neither
// methods nor parameters beside it (INVALID_ARGUMENT).
Expected<TrainSpec> TrainSpecFromProto(const v1::TrainHeader& header);
// The spec on core's TrainParams; INVALID_ARGUMENT for a count beyond int.
Expected<TrainParams> ToTrainParams(const TrainSpec& spec);
// Every field of TrainParameters from core's TrainParams (the inverse of ToTrainParams).
v1::TrainParameters FromTrainParams(const TrainParams& params);

}  // namespace glimpse::wire
