// The open-set problem of the novelty tests: balls and boxes learnt (small codebooks; BoK, USH, VFH and
// the fusion), cans never; new objects of each to classify. Trained once per test binary.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "format3.h"
#include "synthetic.h"

namespace glimpse::test {

inline TrainParams open_set_params() {
  TrainParams p;
  p.methods = {MethodId::kBoK, MethodId::kUSH, MethodId::kVFH, MethodId::kFusion};
  p.bok_clusters = 12;
  return p;
}

inline std::vector<TrainingCloud> without(std::vector<TrainingCloud> clouds, const std::string& category) {
  std::erase_if(clouds, [&](const TrainingCloud& c) { return c.category == category; });
  return clouds;
}

// Balls and boxes learnt; cans never.
struct OpenSet {
  Model model;
  std::vector<TrainingCloud> known, unknown;  // new objects
};

inline const OpenSet& open_set() {
  static const OpenSet s = [] {
    auto m = train(without(synthetic_views(6, 3, 1), "can"), open_set_params());
    EXPECT_TRUE(m.ok()) << m.error().message;
    std::vector<TrainingCloud> test = synthetic_views(5, 2, 2);
    OpenSet out{m.ok() ? *m : Model{}, without(test, "can"), {}};
    for (const TrainingCloud& c : test)
      if (c.category == "can") out.unknown.push_back(c);
    return out;
  }();
  return s;
}

inline std::vector<Classification> classify_all(const Model& model, const std::vector<TrainingCloud>& clouds) {
  std::vector<Classification> out;
  for (const TrainingCloud& c : clouds) {
    auto r = classify(model, c.cloud);
    EXPECT_TRUE(r.ok()) << r.error().message;
    if (r.ok()) out.push_back(*r);
  }
  return out;
}

// A model's bytes read as format `version` says they are (their payload length kept): what a reader of
// that format makes of them.
inline Expected<Model> read_as_format(const std::vector<uint8_t>& bytes, uint32_t version) {
  uint64_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 8);
  return deserialize(with_version(bytes, version, length));
}

}  // namespace glimpse::test
