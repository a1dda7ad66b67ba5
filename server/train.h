// The Train RPC's domain logic, outside the service class: collecting the request stream into a
// training set (with its limits), training + storing a version, and turning core progress into
// percentages and progress messages.
#pragma once

#include <chrono>
#include <functional>
#include <mutex>
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
  wire::TrainSpec spec;
  std::vector<TrainingCloud> clouds;
  size_t points = 0;  // summed over clouds
  size_t keep_set_bytes = 0;  // the largest training set kept beside the model (Limits)
};

// Adds one streamed message: the header first and once, then labelled clouds within the limits.
Status AddTrainRequest(const v1::TrainRequest& msg, const Limits& limits, TrainInput& input);
// Checks the collected input once the stream is closed.
Status CheckTrainInput(const TrainInput& input);

// Trains, serializes and stores a new version of input.name (grown from the spec's base when it names
// one: the base's methods, parameters and kept training set); nothing is stored on any error. A grown
// model's features are those of the sent clouds alone: `features_share` receives their share of the
// call (TrainPercent's) once the base is read.
Expected<ModelRecord> TrainAndStore(const TrainInput& input, const Engine& engine, ModelStore& store,
                                    const ProgressFn& progress, const CancelFn& cancel,
                                    const std::function<void(double)>& features_share = {});

// The percent of a training call the features take when every cloud's are computed.
inline constexpr double kFeaturesPercent = 65;

// Share of the whole call done, 0-100, for a core stage ("features", "codebooks", ...) or one of the
// server's ("received", "storing", "done"), when the features take `features_percent` of the call (the
// other stages share the rest in their usual proportions).
double TrainPercent(std::string_view stage, size_t done, size_t total, double features_percent = kFeaturesPercent);

// The seconds left when `percent` of the call is done after `elapsed_s`: elapsed x the share to do over
// the share done; 0 below 5 % (too little to extrapolate from) and at 100 %.
double SecondsLeft(double percent, double elapsed_s);

// The call's progress as TrainProgress messages: "received" once the clouds are in, core's stages while
// they move (only when the stage changes or the share moves by a point; core may report from worker
// threads, so one write at a time), and "done" with the stored model.
class TrainProgressWriter {
 public:
  using Write = std::function<bool(const v1::TrainProgress&)>;
  explicit TrainProgressWriter(Write write) : write_(std::move(write)) {}

  void Received(size_t clouds);
  void SetFeaturesPercent(double percent);  // a grown model's (TrainAndStore's features_share)
  void Update(const TrainingProgress& p);  // core's ProgressFn
  void Done(const ModelRecord& record);

 private:
  std::mutex mutex_;
  Write write_;
  v1::TrainProgress last_;
  double features_percent_ = kFeaturesPercent;
  std::chrono::steady_clock::time_point received_ = std::chrono::steady_clock::now();
};

}  // namespace glimpse::server
