// The Train RPC's domain logic, outside the service class: collecting the request stream into a
// training set (with its limits), training + storing a version, and turning core progress into
// percentages.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "engine.h"
#include "limits.h"
#include "store.h"

namespace glimpse::server {

struct TrainInput {
  bool has_header = false;
  std::string name;
  std::string description;
  TrainSpec spec;
  std::vector<TrainingCloud> clouds;
  size_t points = 0;  // summed over clouds
};

// Adds one streamed message: the header first and once, then labelled clouds within the limits.
Status AddTrainRequest(const v1::TrainRequest& msg, const Limits& limits, TrainInput& input);
// Checks the collected input once the stream is closed.
Status CheckTrainInput(const TrainInput& input);

// Trains, serializes and stores a new version of input.name; nothing is stored on any error.
Expected<ModelRecord> TrainAndStore(const TrainInput& input, const Engine& engine, ModelStore& store,
                                    const ProgressFn& progress, const CancelFn& cancel);

// Share of the whole call done, 0-100, for a core stage ("features", "codebooks", ...) or one of the
// server's ("received", "storing", "done").
double TrainPercent(std::string_view stage, size_t done, size_t total);

}  // namespace glimpse::server
