// A model grown from a kept training set: the features of the added clouds joined with the base's give
// the model a training of every cloud at once gives (bit for bit from zero; from the base's heads, to
// within the solver's tolerance), and the set's bytes read back whole or not at all.
#include <gtest/gtest.h>

#include <algorithm>

#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/training_set.h"
#include "synthetic.h"

namespace glimpse {
namespace {

using test::small_params;
using test::synthetic_views;

// The model's bytes without its training time (the one thing two trainings of the same rows differ in).
std::vector<uint8_t> bytes_of(Model model) {
  model.stats.seconds = 0;
  return serialize(model);
}

std::vector<TrainingCloud> of_categories(const std::vector<TrainingCloud>& data, const std::vector<std::string>& keep) {
  std::vector<TrainingCloud> out;
  for (const TrainingCloud& c : data)
    if (std::count(keep.begin(), keep.end(), c.category)) out.push_back(c);
  return out;
}

TEST(TrainingSet, GrowingAModelGivesTheModelOfTrainingEveryCloudAtOnce) {
  const std::vector<TrainingCloud> all = synthetic_views(4, 2, 7);
  const std::vector<TrainingCloud> base = of_categories(all, {"ball", "box"});
  std::vector<TrainingCloud> added = of_categories(all, {"can"});
  // One more view of an object the base holds: its tilt continues the object's views.
  added.push_back(base.front());
  added.back().cloud.sensor = Vec3(0, -2, 1);
  const TrainParams params = small_params();

  auto base_set = training_set(base, params);
  ASSERT_TRUE(base_set.ok()) << base_set.error().message;
  auto added_set = training_set(added, params, {}, {}, &*base_set);
  ASSERT_TRUE(added_set.ok()) << added_set.error().message;
  auto joined = join(std::move(*base_set), std::move(*added_set));
  ASSERT_TRUE(joined.ok()) << joined.error().message;
  auto grown = train(std::move(*joined), params);
  ASSERT_TRUE(grown.ok()) << grown.error().message;

  // The same clouds at once, the added objects first: objects in another order, each object's views alike.
  std::vector<TrainingCloud> at_once(added.begin(), added.end() - 1);
  at_once.insert(at_once.end(), base.begin(), base.end());
  at_once.push_back(added.back());
  auto full = train(at_once, params);
  ASSERT_TRUE(full.ok()) << full.error().message;

  EXPECT_EQ(grown->categories, (std::vector<std::string>{"ball", "box", "can"}));
  EXPECT_EQ(grown->stats.clouds, all.size() + 1);
  EXPECT_EQ(bytes_of(*grown), bytes_of(*full));
}

// A model grown from its base starts its logistic decisions where the base's ended (its own head and each
// calibration fold's, by category name) and ends where a training from zero does, to within the solver's
// tolerance: the same winners, scores within a hundredth; everything but the heads bit for bit.
TEST(TrainingSet, AGrownModelStartsWhereItsBaseEndedAndDecidesAsAFullTraining) {
  const std::vector<TrainingCloud> all = synthetic_views(4, 2, 7);
  const std::vector<TrainingCloud> base = of_categories(all, {"ball", "can"});
  const std::vector<TrainingCloud> added = of_categories(all, {"box"});  // a category between the base's
  const TrainParams params = small_params();
  auto base_set = training_set(base, params);
  ASSERT_TRUE(base_set.ok()) << base_set.error().message;
  auto base_model = train(*base_set, params);
  ASSERT_TRUE(base_model.ok()) << base_model.error().message;
  ASSERT_TRUE(base_model->impl->fusion_head.has_value());
  EXPECT_EQ(base_model->impl->fold_heads.size(), static_cast<size_t>(params.calibration_folds));
  auto added_set = training_set(added, params, {}, {}, &*base_set);
  ASSERT_TRUE(added_set.ok()) << added_set.error().message;
  auto joined = join(std::move(*base_set), std::move(*added_set));
  ASSERT_TRUE(joined.ok()) << joined.error().message;
  auto grown = train(*joined, params, {}, {}, &*base_model);
  auto full = train(std::move(*joined), params);
  ASSERT_TRUE(grown.ok() && full.ok());

  const Chi2Logistic& g = *grown->impl->fusion_head;
  const Chi2Logistic& f = *full->impl->fusion_head;
  EXPECT_NE(g.weights, f.weights);  // started elsewhere: not the same steps
  EXPECT_LT((g.weights - f.weights).norm(), 0.05 * f.weights.norm());
  ASSERT_EQ(grown->impl->fold_heads.size(), full->impl->fold_heads.size());
  for (size_t k = 0; k < full->impl->fold_heads.size(); ++k) {
    const Eigen::MatrixXd& fw = full->impl->fold_heads[k].weights;
    EXPECT_LT((grown->impl->fold_heads[k].weights - fw).norm(), 0.05 * fw.norm()) << "fold " << k;
  }
  Model same_heads = *grown;  // the grown model with the full one's heads is the full model
  auto impl = std::make_shared<ModelImpl>(*grown->impl);
  impl->fusion_head = full->impl->fusion_head;
  impl->fold_heads = full->impl->fold_heads;
  impl->calibration = full->impl->calibration;
  impl->novelty = full->impl->novelty;
  same_heads.impl = impl;
  EXPECT_EQ(bytes_of(same_heads), bytes_of(*full));
  for (const TrainingCloud& c : all) {
    auto a = classify(*grown, c.cloud);
    auto b = classify(*full, c.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->winner, b->winner);
    for (size_t k = 0; k < b->scores.size(); ++k) EXPECT_NEAR(a->scores[k], b->scores[k], 0.01);
  }
}

// A grown model whose calibration cannot run (a category of one object) keeps no folds' heads: it keeps
// only what it learnt, never its base's.
TEST(TrainingSet, AGrownModelWithoutCalibrationKeepsNoFoldHeads) {
  const std::vector<TrainingCloud> all = synthetic_views(4, 2, 7);
  const TrainParams params = small_params();
  auto base_set = training_set(of_categories(all, {"ball", "can"}), params);
  ASSERT_TRUE(base_set.ok()) << base_set.error().message;
  auto base_model = train(*base_set, params);
  ASSERT_TRUE(base_model.ok()) << base_model.error().message;
  ASSERT_FALSE(base_model->impl->fold_heads.empty());
  std::vector<TrainingCloud> one_box;
  for (const TrainingCloud& c : of_categories(all, {"box"}))
    if (c.object_id == of_categories(all, {"box"}).front().object_id) one_box.push_back(c);
  auto added_set = training_set(one_box, params, {}, {}, &*base_set);
  ASSERT_TRUE(added_set.ok()) << added_set.error().message;
  auto joined = join(std::move(*base_set), std::move(*added_set));
  ASSERT_TRUE(joined.ok()) << joined.error().message;
  auto grown = train(std::move(*joined), params, {}, {}, &*base_model);
  ASSERT_TRUE(grown.ok()) << grown.error().message;
  EXPECT_EQ(grown->categories.size(), 3u);
  EXPECT_TRUE(grown->impl->fold_heads.empty());
}

TEST(TrainingSet, BytesReadBackToTheSameModel) {
  const std::vector<TrainingCloud> data = synthetic_views(3, 2, 11);
  const TrainParams params = small_params();
  auto set = training_set(data, params);
  ASSERT_TRUE(set.ok()) << set.error().message;
  const std::vector<uint8_t> bytes = serialize(*set);
  auto back = deserialize_training_set(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(serialize(*back), bytes);
  ASSERT_EQ(back->samples.size(), set->samples.size());
  EXPECT_GT(back->samples.front().features.descriptors.size(), 0u);  // keypoints kept (every method)
  auto from_bytes = train(std::move(*back), params);
  auto direct = train(std::move(*set), params);
  ASSERT_TRUE(from_bytes.ok() && direct.ok());
  EXPECT_EQ(bytes_of(*from_bytes), bytes_of(*direct));
}

TEST(TrainingSet, RejectsCorruptTruncatedAndForeignBytes) {
  auto set = training_set(synthetic_views(2, 1, 3), small_params());
  ASSERT_TRUE(set.ok()) << set.error().message;
  std::vector<uint8_t> bytes = serialize(*set);

  std::vector<uint8_t> flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x40;
  auto corrupt = deserialize_training_set(flipped);
  ASSERT_FALSE(corrupt.ok());
  EXPECT_EQ(corrupt.error().code, ErrorCode::kDataLoss);
  EXPECT_NE(corrupt.error().message.find("corrupt"), std::string::npos) << corrupt.error().message;

  for (size_t keep : {size_t{0}, size_t{10}, bytes.size() / 3, bytes.size() - 1}) {
    auto cut = deserialize_training_set(std::span(bytes).first(keep));
    EXPECT_FALSE(cut.ok()) << keep << " bytes";
  }
  std::vector<uint8_t> model_bytes(64, 0);  // a model's header, not a set's
  std::copy_n("GLMPSMDL", 8, model_bytes.begin());
  auto foreign = deserialize_training_set(model_bytes);
  ASSERT_FALSE(foreign.ok());
  EXPECT_NE(foreign.error().message.find("not a Glimpse training set"), std::string::npos);
}

TEST(TrainingSet, FeaturesOfAnotherPipelineVersionAreRefused) {
  auto set = training_set(synthetic_views(2, 1, 5), small_params());
  ASSERT_TRUE(set.ok()) << set.error().message;
  TrainingSet old = *set;
  old.feature_version = kFeaturePipelineVersion - 1;
  auto joined = join(old, *set);
  ASSERT_FALSE(joined.ok());
  EXPECT_EQ(joined.error().code, ErrorCode::kFailedPrecondition);
  auto model = train(std::move(old), small_params());
  ASSERT_FALSE(model.ok());
  EXPECT_EQ(model.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_NE(model.error().message.find("pipeline version"), std::string::npos) << model.error().message;
}

}  // namespace
}  // namespace glimpse
