// Training and classifying on a synthetic problem (balls, boxes, cans): every method, errors, tilts,
// progress, determinism, calibration on held-out objects, size warnings and the scan filters (the byte
// format: test_serialize.cpp; the histograms: test_classifiers.cpp; the decision stage: test_decision.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/train_params.h"
#include "synthetic.h"
#include "trained_model.h"

namespace glimpse {
namespace {

using test::small_params;
using test::trained;
using test::Trained;

double accuracy(const Model& model, const std::vector<TrainingCloud>& test, MethodId method) {
  int correct = 0;
  for (const auto& t : test) {
    auto c = classify(model, t.cloud, method);
    EXPECT_TRUE(c.ok()) << c.error().message;
    if (c.ok() && c->categories[static_cast<size_t>(c->winner)] == t.category) ++correct;
  }
  return static_cast<double>(correct) / static_cast<double>(test.size());
}

class EveryMethod : public ::testing::TestWithParam<MethodId> {};

// Chance is 1/3 on 24 test views of 12 unseen objects. Measured (18 training views, each learnt with
// a tilt of up to 5 degrees): BoK 0.96, BoG 0.96, KGH 1.00, VFH 0.75, ESF 0.92, USH 1.00, size only
// 0.92 (balls, boxes and cans of these sizes differ in height and extent), fusion 1.00. VFH describes
// the view direction as much as the shape, so 18 random views teach it least (as the paper's Table 1).
double floor_for(MethodId m) {
  switch (m) {
    case MethodId::kVFH: return 0.5;
    case MethodId::kFusion: return 0.9;
    default: return 0.8;
  }
}

TEST_P(EveryMethod, SeparatesBallsBoxesAndCans) {
  const Trained& t = trained();
  ASSERT_TRUE(t.model.impl);
  const double acc = accuracy(t.model, t.test, GetParam());
  RecordProperty("accuracy", std::to_string(acc));
  EXPECT_GE(acc, floor_for(GetParam())) << method_name(GetParam());
}

INSTANTIATE_TEST_SUITE_P(Methods, EveryMethod, ::testing::ValuesIn(kAllMethods),
                         [](const auto& info) { return std::string(method_name(info.param)); });

TEST(Classify, ScoresAreADistribution) {
  const Trained& t = trained();
  auto c = classify(t.model, t.test.front().cloud);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->method, t.model.default_method);
  ASSERT_EQ(c->scores.size(), 3u);
  double sum = 0;
  for (double s : c->scores) {
    EXPECT_GT(s, 0);
    EXPECT_LE(s, 1);
    sum += s;
  }
  EXPECT_NEAR(sum, 1, 1e-9);
  EXPECT_EQ(c->categories, (std::vector<std::string>{"ball", "box", "can"}));
  EXPECT_GT(c->points, 0u);
}

TEST(Classify, Errors) {
  const Trained& t = trained();
  auto empty = classify(t.model, Cloud{});
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().code, ErrorCode::kInvalidArgument);
  auto untrained = classify(Model{}, t.test.front().cloud);
  ASSERT_FALSE(untrained.ok());
  EXPECT_EQ(untrained.error().code, ErrorCode::kFailedPrecondition);
  TrainParams only_vfh = small_params();
  only_vfh.methods = {MethodId::kVFH};
  only_vfh.default_method = MethodId::kVFH;
  auto m = train(test::synthetic_views(2, 1, 5), only_vfh);
  ASSERT_TRUE(m.ok()) << m.error().message;
  auto wrong = classify(*m, t.test.front().cloud, MethodId::kBoK);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("bok"), std::string::npos);
  EXPECT_EQ(wrong.error().code, ErrorCode::kFailedPrecondition);  // the model's state, not the cloud
  Cloud line;  // no surface to judge: an error naming why, not a confident winner
  for (int i = 0; i < 3000; ++i) line.points.emplace_back(0.001f * i, 0.002f * i, 0.003f * i);
  auto collinear = classify(t.model, line);
  ASSERT_FALSE(collinear.ok());
  EXPECT_EQ(collinear.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(collinear.error().message.find("collinear"), std::string::npos) << collinear.error().message;
  bool cancelled_called = false;
  auto cancelled = classify(t.model, t.test.front().cloud, std::nullopt, [&] { return cancelled_called = true; });
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.error().code, ErrorCode::kCancelled);
}

// A training cloud's tilt is seeded by its object's name and its place among that object's clouds,
// not by its place in the list: the lab and the service, which list clouds differently, learn the
// same tilted views. Objects listed in another order give the same references, so the same scores.
TEST(Train, TiltsFollowTheObjectNotItsPlaceInTheList) {
  TrainParams p = small_params();
  p.methods = {MethodId::kUSH};
  p.default_method = MethodId::kUSH;
  p.partial_prefixes.clear();
  p.calibration_folds = 0;
  ASSERT_GT(p.tilt_deg, 0.f);
  const std::vector<TrainingCloud> data = test::synthetic_views(2, 2, 13);
  std::vector<TrainingCloud> objects_reversed;  // each object's clouds keep their order
  for (size_t end = data.size(); end > 0; end -= 2) {
    objects_reversed.push_back(data[end - 2]);
    objects_reversed.push_back(data[end - 1]);
  }
  auto a = train(data, p), b = train(objects_reversed, p);
  ASSERT_TRUE(a.ok() && b.ok());
  for (const TrainingCloud& query : test::synthetic_views(1, 2, 14)) {
    auto ca = classify(*a, query.cloud), cb = classify(*b, query.cloud);
    ASSERT_TRUE(ca.ok() && cb.ok());
    ASSERT_EQ(ca->scores.size(), cb->scores.size());
    for (size_t i = 0; i < ca->scores.size(); ++i) EXPECT_NEAR(ca->scores[i], cb->scores[i], 1e-9) << query.object_id;
  }
}

// augmented_prefixes false: an augmented cloud is learnt whole only; the others keep their top-down
// prefixes. The nearest-reference stage holds one reference per learnt row.
TEST(Train, AugmentedCloudsAreLearntWholeOnlyWithoutAugmentedPrefixes) {
  TrainParams p = small_params();
  p.methods = {MethodId::kUSH};
  p.default_method = MethodId::kUSH;
  p.calibration_folds = 0;
  p.decision.kind = DecisionRule::kNearestReference;
  std::vector<TrainingCloud> data = test::synthetic_views(2, 2, 13);
  size_t marked = 0;
  for (size_t i = 0; i < data.size(); i += 2) data[i].augmented = true, ++marked;
  TrainParams whole_only = p;
  whole_only.augmented_prefixes = false;
  auto with = train(data, p), without = train(data, whole_only);
  ASSERT_TRUE(with.ok() && without.ok());
  const Eigen::Index rows_with = with->impl->stages[static_cast<int>(MethodId::kUSH)]->references.rows();
  const Eigen::Index rows_without = without->impl->stages[static_cast<int>(MethodId::kUSH)]->references.rows();
  // Every synthetic view is large enough for all five prefixes.
  EXPECT_EQ(rows_with, Eigen::Index(data.size() * (1 + p.partial_prefixes.size())));
  EXPECT_EQ(rows_without, rows_with - Eigen::Index(marked * p.partial_prefixes.size()));
  auto back = deserialize(serialize(*without));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_FALSE(back->impl->params.augmented_prefixes);
}

TEST(Train, Errors) {
  auto none = train({}, small_params());
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::kInvalidArgument);
  auto data = test::synthetic_views(2, 1, 3);
  for (auto& d : data) d.category = "ball";
  auto one = train(data, small_params());
  ASSERT_FALSE(one.ok());
  EXPECT_NE(one.error().message.find("at least 2 categories"), std::string::npos);
  EXPECT_EQ(one.error().code, ErrorCode::kFailedPrecondition);  // valid data, not enough of it (the proto's code)
  data = test::synthetic_views(2, 1, 3);
  data[1].category.clear();
  auto unnamed = train(data, small_params());
  ASSERT_FALSE(unnamed.ok());
  data = test::synthetic_views(2, 1, 3);
  data[2].cloud.points.resize(3);
  auto tiny = train(data, small_params());
  ASSERT_FALSE(tiny.ok());
  EXPECT_NE(tiny.error().message.find(data[2].object_id), std::string::npos) << tiny.error().message;
  // Codebook sizes the model's reader would refuse are refused before training, not stored unreadable.
  TrainParams big = small_params();
  big.kgh_clusters = 1001;
  auto unreadable = train(test::synthetic_views(2, 1, 3), big);
  ASSERT_FALSE(unreadable.ok());
  EXPECT_EQ(unreadable.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(unreadable.error().message.find("kgh_clusters"), std::string::npos) << unreadable.error().message;
  std::vector<TrainingProgress> seen;
  auto cancelled = train(test::synthetic_views(2, 1, 3), small_params(), [&](const TrainingProgress& p) { seen.push_back(p); },
                         [] { return true; });
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.error().code, ErrorCode::kCancelled);
}

TEST(Train, ReportsProgressAndStatistics) {
  std::vector<TrainingProgress> seen;
  auto data = test::synthetic_views(3, 2, 4);
  auto m = train(data, small_params(), [&](const TrainingProgress& p) { seen.push_back(p); });
  ASSERT_TRUE(m.ok()) << m.error().message;
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().stage, "done");
  EXPECT_EQ(m->stats.clouds, data.size());
  EXPECT_EQ(m->stats.objects, 9u);
  EXPECT_EQ(m->stats.clouds_per_category, (std::vector<size_t>{6, 6, 6}));
  EXPECT_GT(m->stats.keypoints, 0u);
}

TEST(Train, DeterministicWhateverTheThreadCount) {
  auto data = test::synthetic_views(3, 2, 6);
  TrainParams one = small_params(), two = small_params();
  one.threads = 1;
  two.threads = 2;
  auto a = train(data, one), b = train(data, two);
  ASSERT_TRUE(a.ok() && b.ok());
  a->stats.seconds = b->stats.seconds = 0;
  // Thread count is a runtime setting, not part of what was learned.
  auto bytes_a = serialize(*a), bytes_b = serialize(*b);
  EXPECT_EQ(bytes_a, bytes_b);
}

// ---- calibration on held-out folds of the training objects ----

TEST(Calibration, SettleMarginIsTheLowestMarginWhoseDecisionsAreRightEnough) {
  // Margins 1.0 .. 0.1: the top 6 right, then wrong ones mixed in.
  std::vector<std::pair<double, bool>> d = {{1.0, true}, {0.9, true}, {0.8, true}, {0.7, true}, {0.6, true},
                                            {0.5, true}, {0.4, false}, {0.3, true}, {0.2, false}, {0.1, false}};
  EXPECT_DOUBLE_EQ(settle_margin(d, 1.0, 1), 0.5);   // every decision from 0.5 up is right
  EXPECT_DOUBLE_EQ(settle_margin(d, 0.85, 1), 0.3);  // 7 of 8 from 0.3 up
  EXPECT_DOUBLE_EQ(settle_margin(d, 0.5, 1), 0.1);   // 6 of 10
  EXPECT_DOUBLE_EQ(settle_margin(d, 1.0, 20), 0.0);  // too few decisions to say: uncalibrated
  // Never right enough: above every margin seen, so nothing settles.
  std::vector<std::pair<double, bool>> wrong = {{0.5, false}, {0.4, false}, {0.3, true}};
  EXPECT_GT(settle_margin(wrong, 0.9, 1), 0.5);
  // Ties count together: both decisions at 0.6 are in or out at once.
  std::vector<std::pair<double, bool>> tie = {{0.9, true}, {0.6, true}, {0.6, false}, {0.2, true}};
  EXPECT_DOUBLE_EQ(settle_margin(tie, 1.0, 1), 0.9);
}

TEST(Calibration, ATrainedModelMeasuresItsDefaultMethodOnHeldOutObjects) {
  const Trained& t = trained();
  const Calibration& c = calibration(t.model);
  EXPECT_EQ(c.method, t.model.default_method);
  // 18 objects x 3 views x (view + 5 prefixes): every row is held out once.
  EXPECT_GT(c.held_out, 200u);
  EXPECT_GT(c.held_out_accuracy, 0.7);
  EXPECT_GT(c.settle_margin, 0.0);
  EXPECT_LT(c.settle_margin, 1.0);
  TrainParams none = small_params();
  none.calibration_folds = 0;
  auto m = train(test::synthetic_views(3, 2, 1), none);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(calibration(*m).held_out, 0u);
  EXPECT_EQ(calibration(*m).settle_margin, 0.0);
  EXPECT_EQ(calibration(Model{}).held_out, 0u);
}

TEST(Classify, WarnsWhenTheCloudIsFarOutsideTheSizesLearnt) {
  const Trained& t = trained();
  EXPECT_GT(t.model.stats.min_extent_m, 0.f);
  EXPECT_GT(t.model.stats.max_extent_m, t.model.stats.min_extent_m);
  const Cloud& view = t.test.front().cloud;
  auto c = classify(t.model, view);
  ASSERT_TRUE(c.ok());
  EXPECT_TRUE(c->warning.empty()) << c->warning;
  Cloud mm = view;  // the same scan in millimetres
  for (Vec3& p : mm.points) p *= 1000.f;
  if (mm.sensor) *mm.sensor *= 1000.f;
  auto big = classify(t.model, mm);
  ASSERT_TRUE(big.ok()) << big.error().message;
  EXPECT_NE(big->warning.find("millimetres"), std::string::npos) << big->warning;
  EXPECT_NE(big->warning.find("the model knows"), std::string::npos) << big->warning;
  // ... and it is unknown whatever its novelty, at every operating point, the winner still the closest.
  EXPECT_FALSE(c->outside_learnt_sizes);
  EXPECT_TRUE(big->outside_learnt_sizes);
  EXPECT_TRUE(big->unknown);
  EXPECT_GE(big->winner, 0);
  EXPECT_FALSE(big->unknown_reason.empty());
  Classification accepting = *big;
  ASSERT_TRUE(set_known_acceptance(t.model, accepting, 1.0).ok());
  EXPECT_TRUE(accepting.unknown);
  // The size is the reason given, whatever the novelty: a unit is what a person can fix.
  EXPECT_EQ(accepting.unknown_reason.find("size far outside what the model learnt: the cloud spans"), 0u)
      << accepting.unknown_reason;
  EXPECT_EQ(big->unknown_reason.find("size far outside what the model learnt: the cloud spans"), 0u)
      << big->unknown_reason;
  // One stray point far away is dropped by the scan filters: the size judged is the object's, so the
  // answer is the clean view's, not "unknown" by a size the object does not have.
  Cloud stray = view;
  stray.points.push_back(Vec3(1e5f, 1e5f, 1e5f));
  auto strayed = classify(t.model, stray);
  ASSERT_TRUE(strayed.ok()) << strayed.error().message;
  EXPECT_TRUE(strayed->warning.empty()) << strayed->warning;
  EXPECT_FALSE(strayed->outside_learnt_sizes);
  EXPECT_EQ(strayed->winner, c->winner);
  EXPECT_EQ(strayed->unknown, c->unknown);
  TrainingSummary stats;
  stats.min_extent_m = 0.1f, stats.max_extent_m = 2.f;
  Cloud tiny;
  tiny.points = {Vec3(0, 0, 0), Vec3(0.001f, 0.002f, 0.001f)};
  EXPECT_NE(size_warning(stats, tiny).find("only"), std::string::npos);
  EXPECT_TRUE(size_warning(TrainingSummary{}, mm).empty());  // a model that knows no sizes says nothing
}

TEST(Classify, FiltersTheFloorAndStrayPointsAsTheModelRecorded) {
  // A test view standing on a 1.5 m floor patch (5 mm grid) with stray points around: Classify removes
  // the floor and the strays first (the model's scan filters) and decides as on the view alone.
  const Trained& t = trained();
  size_t same = 0, n = 0;
  for (size_t i = 0; i < t.test.size(); i += 3, ++n) {
    const Cloud& view = t.test[i].cloud;
    Cloud scene = view;
    const Bounds b = bounds(view.points);
    const Vec3 c = b.centre();
    for (float x = -0.75f; x <= 0.75f; x += 0.005f)
      for (float y = -0.75f; y <= 0.75f; y += 0.005f) scene.points.emplace_back(c.x() + x, c.y() + y, b.min.z() - 0.005f);
    const std::vector<Vec3> strays = {c + Vec3(0.6f, 0.6f, 0.5f), c + Vec3(-0.5f, 0.3f, 0.9f), c + Vec3(0.2f, -0.6f, -0.4f)};
    scene.points.insert(scene.points.end(), strays.begin(), strays.end());
    auto alone = classify(t.model, view);
    auto filtered = classify(t.model, scene);
    ASSERT_TRUE(alone.ok() && filtered.ok());
    EXPECT_GE(filtered->filters.outliers, strays.size());
    EXPECT_GT(filtered->filters.ground, 90000u) << t.test[i].category;  // 301 x 301 floor points
    same += filtered->winner == alone->winner;
  }
  EXPECT_GE(same, n - 1) << "of " << n;  // the floor's residue (the view's own lowest 4 cm go too) may tip one
}

}  // namespace
}  // namespace glimpse
