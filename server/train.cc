#include "train.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>

#include "convert.h"
#include "glimpse/learning/model.h"
#include "proto/wire/clouds.h"

namespace glimpse::server {
namespace {
constexpr size_t kMaxCategoryBytes = 128;
constexpr size_t kMaxObjectIdBytes = 256;
}  // namespace

Status AddTrainRequest(const v1::TrainRequest& msg, const Limits& limits, TrainInput& input) {
  switch (msg.kind_case()) {
    case v1::TrainRequest::kHeader: {
      if (input.has_header) return invalid_argument("the Train header was sent twice");
      auto spec = wire::TrainSpecFromProto(msg.header());
      if (!spec) return spec.error();
      input.has_header = true;
      input.name = msg.header().model_name();
      input.description = msg.header().description();
      input.spec = std::move(*spec);
      input.keep_set_bytes = limits.max_training_set_bytes;
      return {};
    }
    case v1::TrainRequest::kCloud: {
      if (!input.has_header) return invalid_argument("the first Train message must be the header");
      const v1::LabelledCloud& lc = msg.cloud();
      const size_t index = input.clouds.size();
      if (lc.category().empty()) return invalid_argument("cloud " + std::to_string(index) + " has an empty category");
      if (lc.category().size() > kMaxCategoryBytes)
        return invalid_argument("cloud " + std::to_string(index) + ": category is longer than 128 bytes");
      if (lc.object_id().size() > kMaxObjectIdBytes)
        return invalid_argument("cloud " + std::to_string(index) + ": object_id is longer than 256 bytes");
      if (index >= limits.max_train_clouds)
        return resource_exhausted("more than " + std::to_string(limits.max_train_clouds) + " training clouds");
      auto cloud = wire::CloudFromProto(lc.cloud(), limits.max_points_per_cloud);
      if (!cloud) return Error{cloud.error().code, "cloud " + std::to_string(index) + ": " + cloud.error().message};
      if (input.points + cloud->points.size() > limits.max_train_points)
        return resource_exhausted("training clouds exceed " + std::to_string(limits.max_train_points) + " points in total");
      input.points += cloud->points.size();
      // Without an object id each cloud is its own object (ids cannot clash: real ones have no '#').
      std::string object_id = lc.object_id().empty() ? "#" + std::to_string(index) : lc.object_id();
      input.clouds.push_back({lc.category(), std::move(object_id), std::move(*cloud), lc.augmented()});
      return {};
    }
    case v1::TrainRequest::KIND_NOT_SET: return invalid_argument("empty Train message");
  }
  return invalid_argument("unknown Train message");
}

Status CheckTrainInput(const TrainInput& input) {
  if (!input.has_header) return invalid_argument("Train needs a header message first");
  if (input.clouds.empty()) return invalid_argument("Train received no clouds");
  return {};
}

namespace {

// The version a spec grows, its kept training set, and the spec with the base's methods and parameters.
struct Base {
  std::string name_version;
  std::vector<uint8_t> training_set;
  std::vector<uint8_t> model;  // its bytes: where the grown model's learning starts
  size_t clouds = 0;  // the base's training clouds
};

Expected<Base> BaseOf(wire::TrainSpec& spec, const ModelStore& store) {
  auto record = store.Get(spec.base->name, spec.base->version);
  if (!record) return Error{record.error().code, "base: " + record.error().message};
  Base base{record->name + ":" + std::to_string(record->version), {}, {}, record->stats.clouds};
  if (record->feature_version != kFeaturePipelineVersion)
    return failed_precondition("base " + base.name_version + " was trained with feature pipeline version " +
                               std::to_string(record->feature_version) + ", this server computes version " +
                               std::to_string(kFeaturePipelineVersion) + ": train it again from its clouds");
  if (record->training_set_bytes == 0)
    return failed_precondition("base " + base.name_version +
                               " keeps no training set (stored by an older server, or larger than "
                               "--max-training-set-bytes): train it again from its clouds with the added ones");
  auto set = store.TrainingSet(record->id);
  if (!set) return Error{set.error().code, "base " + base.name_version + ": " + set.error().message};
  base.training_set = std::move(*set);
  auto blob = store.Blob(record->id);
  if (!blob) return Error{blob.error().code, "base " + base.name_version + ": " + blob.error().message};
  base.model = std::move(*blob);
  spec.methods = record->methods;
  spec.default_method = record->default_method;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;
  if (!google::protobuf::util::JsonStringToMessage(record->params, &spec.parameters, options).ok())
    return data_loss("base " + base.name_version + ": its stored training parameters do not parse");
  return base;
}

}  // namespace

Expected<ModelRecord> TrainAndStore(const TrainInput& input, const Engine& engine, ModelStore& store,
                                    const ProgressFn& progress, const CancelFn& cancel,
                                    const std::function<void(double)>& features_share) {
  wire::TrainSpec spec = input.spec;
  Base base;
  if (spec.base) {
    auto found = BaseOf(spec, store);
    if (!found) return found.error();
    base = std::move(*found);
    if (features_share)
      features_share(kFeaturesPercent * static_cast<double>(input.clouds.size()) /
                     static_cast<double>(input.clouds.size() + base.clouds));
  }
  auto trained = engine.train(input.clouds, spec, base.training_set, base.model, input.keep_set_bytes, progress, cancel);
  if (!trained) return trained.error();
  const Model* model = &trained->model;
  if (cancel && cancel()) return cancelled("training was cancelled");
  if (progress) progress({"storing", 0, 1});
  NewModel row;
  row.name = input.name;
  row.grown_from = base.name_version;
  row.training_set = std::move(trained->training_set);
  row.description = input.description;
  row.methods = model->methods;
  row.default_method = model->default_method;
  row.stats = model->stats;
  if (row.stats.categories.empty()) row.stats.categories = model->categories;
  row.feature_version = model->feature_version;
  // What training used (every field), so ModelInfo shows it rather than an echo of the request; the
  // views' density as the sender gave it (training does not read it).
  v1::TrainParameters used = spec.parameters;
  if (engine.effective_parameters) {
    auto effective = engine.effective_parameters(spec);
    if (!effective) return effective.error();
    used = std::move(*effective);
  }
  if (spec.parameters.has_view_density()) used.set_view_density(spec.parameters.view_density());
  (void)google::protobuf::util::MessageToJsonString(used, &row.params);
  row.blob = engine.serialize(*model);
  if (row.blob.empty()) return internal_error("serialized model is empty");
  // A model stored becomes the name's default: one that would not read back would break every Classify of
  // the name, so it is read back before it is stored.
  if (engine.deserialize) {
    if (auto back = engine.deserialize(row.blob); !back)
      return internal_error("the trained model does not read back (" + back.error().message + "); nothing was stored");
  }
  return store.Put(row);
}

double TrainPercent(std::string_view stage, size_t done, size_t total, double features_percent) {
  struct Span {
    std::string_view stage;
    double from, to;
  };
  // The shares of the time a training run of the default methods takes (SHREC with the zoo on 2 cores:
  // features 65 %, the stages 4 % and the logistic decision 9 % ("centres", its last step), calibration
  // 19 % (a step per inner fold), the novelty model 3 %), which SecondsLeft extrapolates; in order, so a
  // progress bar only moves on.
  static constexpr Span kSpans[] = {{"received", 0, 0},     {"features", 0, 65},      {"codebooks", 65, 66},
                                    {"centres", 66, 79},    {"calibration", 79, 97}, {"novelty", 97, 99.5},
                                    {"storing", 99.5, 99.9}, {"done", 100, 100}};
  for (const Span& s : kSpans) {
    if (s.stage != stage) continue;
    double f = total > 0 ? std::clamp(static_cast<double>(done) / static_cast<double>(total), 0.0, 1.0) : 0.0;
    // The spans as measured, with the features' end moved to features_percent and the rest scaled alike.
    const double p = std::clamp(features_percent, 0.0, 100.0);
    auto moved = [&](double x) {
      return x <= kFeaturesPercent ? x * p / kFeaturesPercent : p + (x - kFeaturesPercent) * (100 - p) / (100 - kFeaturesPercent);
    };
    return moved(s.from) + f * (moved(s.to) - moved(s.from));
  }
  return -1;  // unknown stage: the caller keeps its last value
}

double SecondsLeft(double percent, double elapsed_s) {
  if (!(percent >= 5 && percent < 100) || !(elapsed_s >= 0)) return 0;
  return elapsed_s * (100 - percent) / percent;
}

void TrainProgressWriter::Received(size_t clouds) {
  std::lock_guard lock(mutex_);
  received_ = std::chrono::steady_clock::now();
  last_.set_stage("received");
  last_.set_clouds_received(clouds);
  write_(last_);
}

void TrainProgressWriter::SetFeaturesPercent(double percent) {
  std::lock_guard lock(mutex_);
  features_percent_ = percent;
}

void TrainProgressWriter::Update(const TrainingProgress& p) {
  if (p.stage == "done") return;  // core's end; the call is done once the model is stored
  std::lock_guard lock(mutex_);
  if (p.stage == "features") last_.set_features_extracted(p.done);
  if (p.stage == "codebooks") {
    last_.set_codebooks_fitted(p.done);
    last_.set_codebooks_total(p.total);
  }
  const double percent =
      std::max(last_.percent(), std::min(99.0, TrainPercent(p.stage, p.done, p.total, features_percent_)));
  const bool moved = p.stage != last_.stage() || percent >= last_.percent() + 1.0 || p.done == p.total;
  last_.set_stage(p.stage);
  last_.set_stage_done(p.done);
  last_.set_stage_total(p.total);
  if (!moved) return;
  last_.set_percent(percent);
  last_.set_seconds_left(
      SecondsLeft(percent, std::chrono::duration<double>(std::chrono::steady_clock::now() - received_).count()));
  write_(last_);
}

void TrainProgressWriter::Done(const ModelRecord& record) {
  std::lock_guard lock(mutex_);
  last_.set_stage("done");
  last_.set_stage_done(1);
  last_.set_stage_total(1);
  last_.set_percent(100);
  last_.set_seconds_left(0);
  ToProto(record, last_.mutable_model());
  write_(last_);
}

}  // namespace glimpse::server
