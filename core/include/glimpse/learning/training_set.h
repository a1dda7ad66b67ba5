// What a model learnt from, kept beside it so the model can grow (glimpse train --base): each given
// cloud's category, object, relative density and augmented mark, and the features of every row learnt
// (the clouds as learnt and as seen, and their top-down prefixes). Growing computes the features of the
// added clouds alone; the model learnt from the joined set is the one a training of every cloud at once
// gives, whatever order the objects came in.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "glimpse/expected.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/learning/training.h"

namespace glimpse {

// A training cloud as given, without its points: what the learnt density and the statistics count.
struct GivenCloud {
  std::string category;
  std::string object_id;
  double relative_density = 0;  // relative_density() of its points (0: too few points)
  bool augmented = false;
};

struct TrainingSet {
  uint32_t feature_version = kFeaturePipelineVersion;  // what the samples' features were computed with
  std::vector<GivenCloud> clouds;
  std::vector<TrainingSample> samples;  // the rows learnt: each cloud whole and its top-down prefixes
};

// The features of every training cloud (train() = training_set() then train() of the set). `base`: the
// set the clouds are added to, whose views of an object the added views of that object follow (each
// view's tilt is seeded by its place among its object's views).
Expected<TrainingSet> training_set(const std::vector<TrainingCloud>& data, const TrainParams& params,
                                   const ProgressFn& progress = {}, const CancelFn& cancel = {},
                                   const TrainingSet* base = nullptr);

// Learns a model from a set: its rows ordered by category and object first (so the objects' order does
// not matter), the scan filters' density the median of its clouds' (unless params set one). `start`: the
// model the set's first part learnt (the base it grows from): its solvers start there (train_on_features,
// training.h), and learning takes a fraction of the time.
Expected<Model> train(TrainingSet set, const TrainParams& params, const ProgressFn& progress = {},
                      const CancelFn& cancel = {}, const Model* start = nullptr);

// `base`'s clouds and rows, then `added`'s. A failed precondition when their feature versions differ.
Expected<TrainingSet> join(TrainingSet base, TrainingSet added);

// Versioned little-endian bytes ("GLMPSSET", zlib-compressed, CRC-32 checked); features stay binary32,
// as computed. Empty when compression fails.
std::vector<uint8_t> serialize(const TrainingSet& set);
// Truncated, corrupt or foreign bytes are an error (DATA_LOSS or INVALID_ARGUMENT), never UB.
Expected<TrainingSet> deserialize_training_set(std::span<const uint8_t> bytes);

}  // namespace glimpse
