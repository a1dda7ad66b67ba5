// The model's byte format: a round trip gives identical scores, corrupt, truncated and hostile bytes are
// refused, models of other writers (no scan filters, another feature pipeline) read as they learnt, and the
// fuzzer's seeds load.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "format3.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "trained_model.h"

namespace glimpse {
namespace {

using test::trained;
using test::Trained;

// A model without the "filters.enabled" parameter (its writer knew no scan filters) classifies unfiltered,
// as it learnt.
// Made from today's bytes with that name changed (an unknown name is ignored) and the CRC-32 redone.
TEST(Serialize, AModelFromBeforeTheScanFiltersReadsUnfiltered) {
  const std::vector<uint8_t> bytes = test::without_parameter(serialize(trained().model), "filters.enabled");
  ASSERT_FALSE(bytes.empty());
  auto old = deserialize(bytes);
  ASSERT_TRUE(old.ok()) << old.error().message;
  // A view with three stray points: today's model drops them, the old one keeps every point.
  Cloud view = trained().test[0].cloud;
  const Vec3 c = bounds(view.points).centre();
  for (const Vec3& d : {Vec3(0.6f, 0.6f, 0.5f), Vec3(-0.5f, 0.3f, 0.9f), Vec3(0.2f, -0.6f, -0.4f)}) view.points.push_back(c + d);
  auto now = classify(trained().model, view), before = classify(*old, view);
  ASSERT_TRUE(now.ok() && before.ok());
  EXPECT_GE(now->filters.outliers, 3u);
  EXPECT_EQ(before->filters.input, 0u);  // no filter ran
  EXPECT_EQ(before->points, now->points + now->filters.outliers);
}

TEST(Classify, RefusesAModelOfAnotherFeaturePipelineVersion) {
  Model old = trained().model;
  old.feature_version = kFeaturePipelineVersion - 1;
  auto c = classify(old, trained().test.front().cloud);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_NE(c.error().message.find("feature pipeline version " + std::to_string(kFeaturePipelineVersion - 1)),
            std::string::npos) << c.error().message;
  auto back = deserialize(serialize(old));  // the version is stored
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->feature_version, kFeaturePipelineVersion - 1);
}

TEST(Serialize, RoundTripGivesIdenticalScores) {
  const Trained& t = trained();
  const std::vector<uint8_t> bytes = serialize(t.model);
  auto back = deserialize(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->categories, t.model.categories);
  EXPECT_EQ(back->methods, t.model.methods);
  EXPECT_EQ(back->stats.clouds, t.model.stats.clouds);
  EXPECT_EQ(calibration(*back).settle_margin, calibration(t.model).settle_margin);
  EXPECT_EQ(calibration(*back).held_out, calibration(t.model).held_out);
  EXPECT_EQ(serialize(*back), bytes);
  for (MethodId m : t.model.methods) {
    for (size_t i = 0; i < 4; ++i) {
      auto a = classify(t.model, t.test[i * 5].cloud, m);
      auto b = classify(*back, t.test[i * 5].cloud, m);
      ASSERT_TRUE(a.ok() && b.ok());
      EXPECT_EQ(a->scores, b->scores) << method_name(m);
    }
  }
}

// Format 12 stores the decision stages' references as binary32, the precision training keeps them at: a
// model of format 11 (binary64 references) reads and decides alike, and takes more bytes.
TEST(Serialize, ReferencesAreBinary32AndAFormat11ModelReadsAlike) {
  const Trained& t = trained();
  const std::vector<uint8_t> twelve = test::format_12_bytes(t.model), eleven = test::format_11_bytes(t.model);
  ASSERT_FALSE(eleven.empty());
  size_t references = 0;
  for (const auto& stage : t.model.impl->stages)
    if (stage) {
      references += static_cast<size_t>(stage->references.size());
      EXPECT_TRUE((stage->references.array() == stage->references.cast<float>().cast<double>().array()).all());
    }
  EXPECT_EQ(eleven.size(), twelve.size() + 4 * references);
  auto old = deserialize(eleven);
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_EQ(test::format_12_bytes(*old), twelve);  // read as binary64, written again as binary32: the same bytes
  for (size_t i = 0; i < 4; ++i) {
    auto a = classify(t.model, t.test[i * 5].cloud), b = classify(*old, t.test[i * 5].cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
  }
}

// Format 14 stores the decision stages' references as binary16, the precision training keeps them at: a
// model of format 13 (binary32 references) reads and decides alike, and takes about twice the bytes.
TEST(Serialize, ReferencesAreBinary16AndAFormat13ModelReadsAlike) {
  const Trained& t = trained();
  const std::vector<uint8_t> fourteen = serialize(t.model), thirteen = test::format_13_bytes(t.model);
  ASSERT_FALSE(thirteen.empty());
  size_t references = 0, stages = 0;
  for (const auto& stage : t.model.impl->stages)
    if (stage) {
      ++stages;
      references += static_cast<size_t>(stage->references.size());
      EXPECT_TRUE(is_binary16(stage->references));
      EXPECT_GT(stage->references.cwiseAbs().maxCoeff(), 0.0);
    }
  ASSERT_GT(stages, 0u);
  if (t.model.impl->novelty)
    for (const auto& stage : t.model.impl->novelty->stages)
      if (stage) ++stages, references += static_cast<size_t>(stage->references.size());
  EXPECT_EQ(thirteen.size(), fourteen.size() + 2 * references - stages);
  auto old = deserialize(thirteen);
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_EQ(serialize(*old), fourteen);  // read as binary32, written again as binary16: the same bytes
  for (size_t i = 0; i < 4; ++i) {
    auto a = classify(t.model, t.test[i * 5].cloud), b = classify(*old, t.test[i * 5].cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
  }
}

// References beyond binary16's range are kept, and stored, at binary32.
TEST(Serialize, ReferencesBeyondBinary16KeepBinary32) {
  Eigen::MatrixXd big(2, 2);
  big << 0.1, -70000.25, 3.0, 1e-3;
  const Eigen::MatrixXd kept = stored_precision(big);
  EXPECT_EQ(kept, big.cast<float>().cast<double>().eval());
  EXPECT_FALSE(is_binary16(kept));
  Eigen::MatrixXd small = big;
  small(0, 1) = -700.25;
  EXPECT_TRUE(is_binary16(stored_precision(small)));
  EXPECT_NE(stored_precision(small)(0, 0), 0.1);  // 0.1 has no binary16 value
  EXPECT_NEAR(stored_precision(small)(0, 0), 0.1, 1e-4);
  // A model whose stage holds such a value stores that stage at binary32 and reads it back whole.
  Model copy = trained().model;
  auto impl = std::make_shared<ModelImpl>(*copy.impl);
  DecisionStage* stage = nullptr;
  for (auto& s : impl->stages)
    if (s && !stage) stage = &*s;
  ASSERT_NE(stage, nullptr);
  stage->references(0, 0) = -70000.25;
  copy.impl = impl;
  auto back = deserialize(serialize(copy));
  ASSERT_TRUE(back.ok()) << back.error().message;
  for (size_t m = 0; m < copy.impl->stages.size(); ++m)
    if (copy.impl->stages[m]) EXPECT_EQ(back->impl->stages[m]->references, copy.impl->stages[m]->references) << m;
}

// The calibration folds' heads (where a grown model starts) come back from the bytes as binary32; a
// format-12 model reads without them and decides alike.
TEST(Serialize, TheFoldHeadsComeBackAndAFormat12ModelReadsWithoutThem) {
  const Trained& t = trained();
  ASSERT_TRUE(t.model.impl->fusion_head.has_value());
  const size_t folds = t.model.impl->fold_heads.size();
  ASSERT_GT(folds, 0u);
  auto back = deserialize(serialize(t.model));
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->impl->fold_heads.size(), folds);
  for (size_t k = 0; k < folds; ++k) {
    const Eigen::MatrixXd& w = t.model.impl->fold_heads[k].weights;
    EXPECT_EQ(back->impl->fold_heads[k].weights, w.cast<float>().cast<double>().eval());
    EXPECT_EQ(back->impl->fold_heads[k].bias, t.model.impl->fold_heads[k].bias);
  }
  auto twelve = deserialize(test::format_12_bytes(t.model));
  ASSERT_TRUE(twelve.ok()) << twelve.error().message;
  EXPECT_TRUE(twelve->impl->fold_heads.empty());
  auto a = classify(t.model, t.test.front().cloud), b = classify(*twelve, t.test.front().cloud);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->scores, b->scores);
}

TEST(Serialize, RejectsCorruptAndTruncatedBytes) {
  const std::vector<uint8_t> bytes = serialize(trained().model);
  for (size_t cut : {size_t{0}, size_t{7}, size_t{23}, bytes.size() / 2, bytes.size() - 1}) {
    auto r = deserialize(std::span(bytes.data(), cut));
    ASSERT_FALSE(r.ok()) << "truncated at " << cut;
    EXPECT_EQ(r.error().code, ErrorCode::kDataLoss);
  }
  for (size_t pos : {size_t{3}, size_t{9}, size_t{30}, bytes.size() / 3, bytes.size() - 2}) {
    std::vector<uint8_t> flipped = bytes;
    flipped[pos] ^= 0x10;
    auto r = deserialize(flipped);
    ASSERT_FALSE(r.ok()) << "flipped byte " << pos;
    EXPECT_EQ(r.error().code, ErrorCode::kDataLoss);
    EXPECT_FALSE(r.error().message.empty());
  }
}

// A regression input of tests/fuzz: a stored parameter of 9.6e220, which an int cannot hold (casting it
// would be undefined behaviour).
TEST(Serialize, RejectsParametersOutsideTheirType) {
  const std::string path = GLIMPSE_SOURCE_DIR "/tests/fuzz/corpus/deserialize/regress-float-cast-overflow-parameter.glmpsmdl";
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path;
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto r = deserialize(bytes);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kDataLoss);
}

// The deserializer's fuzz seeds (tests/fuzz/corpus/deserialize, written by fuzz_make_model_seeds) are
// payloads of real models: framed as the format serialize writes, each loads, so the fuzzer starts from
// inputs that reach the whole parser. Rewrite them when the format changes.
TEST(Serialize, TheFuzzersModelSeedsLoadInTheCurrentFormat) {
  const std::vector<uint8_t> empty = serialize(Model{});
  uint32_t version = 0;
  std::memcpy(&version, empty.data() + 8, 4);
  for (const char* name : {"bok", "esf", "vfh-kgh", "fusion", "fusion-novelty"}) {
    const std::string path = GLIMPSE_SOURCE_DIR "/tests/fuzz/corpus/deserialize/" + std::string(name);
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << path;
    const std::vector<uint8_t> payload((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<uint8_t> bytes(empty.begin(), empty.begin() + 20);
    bytes.insert(bytes.end(), payload.begin(), payload.end());
    bytes.resize(bytes.size() + 4);
    auto model = deserialize(test::with_version(bytes, version, payload.size()));
    ASSERT_TRUE(model.ok()) << name << ": " << model.error().message;
    if (std::string(name) == "fusion-novelty") {
      EXPECT_NE(&novelty_calibration(*model), &calibration(*model)) << name;
    }
  }
}

}  // namespace
}  // namespace glimpse
