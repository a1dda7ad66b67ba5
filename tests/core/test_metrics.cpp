// The decision metrics shared by `glimpse evaluate` and the lab: accuracy, balanced accuracy, confusion,
// their object-bootstrap intervals and AUROC, on hand-made decisions; and the stratified folds that
// calibration and cross-validation deal objects to.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/decisions.h"
#include "glimpse/learning/calibration.h"
#include "glimpse/learning/metrics.h"
#include "glimpse/learning/model.h"

namespace glimpse {
namespace {

using testing::decision;

std::vector<std::string> shrec_like_categories(size_t per_category) {
  std::vector<std::string> cats;
  for (const char* c : {"human", "chair", "table", "mechanic", "fourleg"})
    for (size_t i = 0; i < per_category; ++i) cats.push_back(c);
  return cats;
}

TEST(StratifiedFolds, EveryFoldHoldsFourObjectsOfEveryCategoryForShrec) {
  const std::vector<std::string> cats = shrec_like_categories(20);
  const std::vector<int> fold = stratified_folds(cats, 5, 42);
  ASSERT_EQ(fold.size(), cats.size());
  std::map<std::pair<std::string, int>, int> count;
  for (size_t i = 0; i < cats.size(); ++i) {
    ASSERT_GE(fold[i], 0);
    ASSERT_LT(fold[i], 5);
    ++count[{cats[i], fold[i]}];
  }
  EXPECT_EQ(count.size(), 25u);
  for (const auto& [key, n] : count) EXPECT_EQ(n, 4) << key.first << " fold " << key.second;
}

TEST(StratifiedFolds, UnevenCategoriesDifferByAtMostOnePerFold) {
  std::vector<std::string> cats = shrec_like_categories(7);
  cats.push_back("extra");
  const std::vector<int> fold = stratified_folds(cats, 3, 1);
  std::map<std::string, std::vector<int>> per;
  for (size_t i = 0; i < cats.size(); ++i) {
    per[cats[i]].resize(3, 0);
    ++per[cats[i]][fold[i]];
  }
  for (const auto& [c, n] : per) {
    EXPECT_LE(*std::max_element(n.begin(), n.end()) - *std::min_element(n.begin(), n.end()), 1) << c;
  }
  std::vector<int> sizes(3, 0);  // folds stay balanced overall too
  for (int f : fold) ++sizes[f];
  EXPECT_LE(*std::max_element(sizes.begin(), sizes.end()) - *std::min_element(sizes.begin(), sizes.end()), 1);
}

// Calibration's folds: a category added to the training objects (here between the others by name)
// moves no other category's objects to another fold, as stratified_folds' rotation would.
TEST(CalibrationFolds, ACategoryAddedMovesNoOtherCategorysObjects) {
  std::vector<std::string> cats = shrec_like_categories(7);  // five categories of 7 objects
  const std::vector<int> before = calibration_folds(cats, 4, 42);
  std::vector<std::string> more = cats;
  for (int i = 0; i < 5; ++i) more.push_back("dog");  // "chair" < "dog" < "fourleg"
  const std::vector<int> after = calibration_folds(more, 4, 42);
  EXPECT_EQ(std::vector<int>(after.begin(), after.begin() + static_cast<std::ptrdiff_t>(cats.size())), before);
  std::map<std::string, std::vector<int>> per;  // still stratified: at most one apart per category
  for (size_t i = 0; i < more.size(); ++i) {
    per[more[i]].resize(4, 0);
    ++per[more[i]][after[i]];
  }
  for (const auto& [c, n] : per) EXPECT_LE(*std::max_element(n.begin(), n.end()) - *std::min_element(n.begin(), n.end()), 1) << c;
  // stratified_folds' rotation moves the categories after the added one.
  const std::vector<int> rotated = stratified_folds(more, 4, 42);
  EXPECT_NE(std::vector<int>(rotated.begin(), rotated.begin() + static_cast<std::ptrdiff_t>(cats.size())),
            stratified_folds(cats, 4, 42));
}

TEST(StratifiedFolds, DeterministicPerSeedAndShuffledAcrossSeeds) {
  const std::vector<std::string> cats = shrec_like_categories(20);
  EXPECT_EQ(stratified_folds(cats, 5, 7), stratified_folds(cats, 5, 7));
  EXPECT_NE(stratified_folds(cats, 5, 7), stratified_folds(cats, 5, 8));
  EXPECT_TRUE(stratified_folds({}, 5, 7).empty());
}

TEST(Metrics, AccuracyAndConfusionOnAHandMadeList) {
  std::vector<StageDecision> d = {
      decision("full", MethodId::kBoK, 0, 0), decision("full", MethodId::kBoK, 0, 0), decision("full", MethodId::kBoK, 0, 1),
      decision("full", MethodId::kBoK, 0, -1),  // no decision: wrong, in no column
      decision("full", MethodId::kBoK, 1, 1),   decision("full", MethodId::kBoK, 2, 0),
      decision("10kp", MethodId::kBoK, 0, 1),   decision("full", MethodId::kVFH, 0, 0),
  };
  const Tally t = accuracy(d, "full", MethodId::kBoK);
  EXPECT_EQ(t.total, 6u);
  EXPECT_EQ(t.correct, 3u);
  EXPECT_DOUBLE_EQ(t.percent(), 50.0);
  EXPECT_EQ(accuracy(d, "10kp", MethodId::kBoK).correct, 0u);
  EXPECT_EQ(accuracy(d, "full", MethodId::kVFH).correct, 1u);
  EXPECT_EQ(accuracy(d, "20%", MethodId::kVFH).total, 0u);
  EXPECT_DOUBLE_EQ(accuracy(d, "20%", MethodId::kVFH).percent(), 0.0);

  const auto c = confusion_percent(d, "full", MethodId::kBoK, 3);
  EXPECT_DOUBLE_EQ(c[0][0], 50.0);
  EXPECT_DOUBLE_EQ(c[0][1], 25.0);
  EXPECT_DOUBLE_EQ(c[0][2], 0.0);
  EXPECT_DOUBLE_EQ(c[1][1], 100.0);
  EXPECT_DOUBLE_EQ(c[2][0], 100.0);
}

TEST(OpenSet, AurocRanksUnknownAboveKnownWithTiesHalf) {
  EXPECT_DOUBLE_EQ(auroc({1, 2, 3}, {4, 5}), 1.0);
  EXPECT_DOUBLE_EQ(auroc({4, 5}, {1, 2, 3}), 0.0);
  EXPECT_DOUBLE_EQ(auroc({1, 2}, {2}), 0.75);  // one below, one tied
  EXPECT_DOUBLE_EQ(auroc({}, {1}), 0.5);
  EXPECT_DOUBLE_EQ(auroc({1.0}, {INFINITY}), 1.0);
}

TEST(Metrics, BalancedAccuracyWeighsEveryCategoryTheSame) {
  std::vector<StageDecision> d;
  auto add = [&](int truth, int winner) {
    StageDecision x;
    x.stage = "full";
    x.method = MethodId::kUSH;
    x.truth = truth;
    x.winner = winner;
    d.push_back(x);
  };
  for (int i = 0; i < 9; ++i) add(0, 0);  // category 0: 9 of 9
  add(1, 0);                              // category 1: 0 of 1
  EXPECT_NEAR(accuracy(d, "full", MethodId::kUSH).percent(), 90.0, 1e-9);
  EXPECT_NEAR(balanced_accuracy(d, "full", MethodId::kUSH, 3), 50.0, 1e-9);  // category 2 has no view: left out
  EXPECT_EQ(balanced_accuracy(d, "20%", MethodId::kUSH, 3), 0.0);
}

TEST(Metrics, AccuracyIntervalResamplesObjectsNotViews) {
  // 20 objects of 6 views, 12 views wrong: on two objects (all their views) or one view on each of 12.
  auto views = [](bool clustered) {
    std::vector<StageDecision> d;
    for (int o = 0; o < 20; ++o)
      for (int v = 0; v < 6; ++v) {
        const bool wrong = clustered ? o < 2 : (o < 12 && v == 0);
        d.push_back(decision("10%", MethodId::kFusion, o % 5, wrong ? (o + 1) % 5 : o % 5, o));
      }
    d.push_back(decision("10%", MethodId::kFusion, -1, 0, 99));  // no learnt category: left out
    d.push_back(decision("10%", MethodId::kVFH, 0, 1, 0));     // another method
    return d;
  };
  const auto clustered = views(true), spread = views(false);
  ASSERT_NEAR(accuracy(clustered, "10%", MethodId::kFusion).percent(), 90.0, 1e-9);
  ASSERT_NEAR(accuracy(spread, "10%", MethodId::kFusion).percent(), 90.0, 1e-9);
  const AccuracyInterval c = accuracy_interval(clustered, "10%", MethodId::kFusion);
  const AccuracyInterval s = accuracy_interval(spread, "10%", MethodId::kFusion);
  for (const AccuracyInterval& i : {c, s}) {
    EXPECT_LE(i.low, 90.0);
    EXPECT_GE(i.high, 90.0);
  }
  // Errors that come in whole objects leave accuracy far less certain than the same errors spread out.
  EXPECT_GT(c.high - c.low, 2 * (s.high - s.low)) << c.low << "-" << c.high << " against " << s.low << "-" << s.high;
  EXPECT_GE(c.low, 70.0);  // 6 of 20 draws on the two wrong objects would read 70 %: far in the tail
  const AccuracyInterval again = accuracy_interval(clustered, "10%", MethodId::kFusion);
  EXPECT_EQ(again.low, c.low);
  EXPECT_EQ(again.high, c.high);
  const AccuracyInterval wider = accuracy_interval(clustered, "10%", MethodId::kFusion, 0.99);
  EXPECT_LE(wider.low, c.low);
  EXPECT_GE(wider.high, c.high);

  std::vector<StageDecision> right = {decision("full", MethodId::kUSH, 0, 0, 0), decision("full", MethodId::kUSH, 1, 1, 1)};
  const AccuracyInterval all = accuracy_interval(right, "full", MethodId::kUSH);
  EXPECT_EQ(all.low, 100.0);
  EXPECT_EQ(all.high, 100.0);
  const AccuracyInterval none = accuracy_interval(right, "20%", MethodId::kUSH);
  EXPECT_EQ(none.low, 0.0);
  EXPECT_EQ(none.high, 0.0);
}

TEST(Metrics, PairedDifferenceResamplesObjectsWithBothRunsViews) {
  // 20 objects of 6 views, all right before; after, 12 views turn wrong: all of two objects, or one view on
  // each of 12. Either way -10 points.
  auto views = [](bool clustered) {
    std::vector<PairedView> v;
    for (int o = 0; o < 20; ++o)
      for (int k = 0; k < 6; ++k) v.push_back({o, true, !(clustered ? o < 2 : (o < 12 && k == 0))});
    return v;
  };
  const PairedDifference c = paired_difference(views(true)), s = paired_difference(views(false));
  for (const PairedDifference& d : {c, s}) {
    EXPECT_EQ(d.views, 120u);
    EXPECT_EQ(d.units, 20u);
    EXPECT_NEAR(d.before, 100.0, 1e-9);
    EXPECT_NEAR(d.after, 90.0, 1e-9);
    EXPECT_NEAR(d.difference, -10.0, 1e-9);
    EXPECT_EQ(d.turned_wrong, 12u);
    EXPECT_EQ(d.turned_right, 0u);
    // No object got better: no resample can read a gain; the difference lies inside.
    EXPECT_LE(d.interval.high, 0.0);
    EXPECT_LE(d.interval.low, -10.0);
    EXPECT_GE(d.interval.high, -10.0);
  }
  // A loss on two whole objects is far less certain than the same views lost over twelve.
  EXPECT_GT(c.interval.high - c.interval.low, 2 * (s.interval.high - s.interval.low));
  // Paired: views that swap between two objects of the same runs move nothing, whatever is drawn.
  std::vector<PairedView> swapped;
  for (int o = 0; o < 10; ++o)
    for (int k = 0; k < 6; ++k) swapped.push_back({o, k < 3, k < 3});
  swapped.push_back({10, true, false});
  swapped.push_back({10, false, true});
  const PairedDifference none = paired_difference(swapped);
  EXPECT_EQ(none.difference, 0.0);
  EXPECT_EQ(none.turned_right, 1u);
  EXPECT_EQ(none.turned_wrong, 1u);
  EXPECT_EQ(none.interval.low, 0.0);
  EXPECT_EQ(none.interval.high, 0.0);
  // The same seed, the same interval; a wider level, a wider one.
  const PairedDifference again = paired_difference(views(true));
  EXPECT_EQ(again.interval.low, c.interval.low);
  EXPECT_EQ(again.interval.high, c.interval.high);
  const PairedDifference wider = paired_difference(views(true), 0.99);
  EXPECT_LE(wider.interval.low, c.interval.low);
  EXPECT_GE(wider.interval.high, c.interval.high);
  const PairedDifference empty = paired_difference({});
  EXPECT_EQ(empty.views, 0u);
  EXPECT_EQ(empty.interval.low, 0.0);
  EXPECT_EQ(empty.interval.high, 0.0);
}

}  // namespace
}  // namespace glimpse
