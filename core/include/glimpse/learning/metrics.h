// What a decision of a test view records, and the metrics over many: accuracy and balanced accuracy per
// stage and method, the confusion table, and how far accuracy (or a change of it) could move with another
// draw of test objects. `glimpse evaluate` and the lab's report share them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/features/methods.h"

namespace glimpse {

struct StageDecision {
  int fold = 0;
  int object = 0;  // index into the evaluated objects
  int view = 0;
  std::string stage;
  MethodId method = MethodId::kFusion;
  double visible_fraction = 0;  // prefix points / full 3D cloud points
  size_t points = 0;            // prefix points
  size_t keypoints = 0;         // keypoints found on the prefix
  int truth = 0;                // index into the report's categories; -1 for an object of no learnt category
  int unknown_class = -1;       // that object's index into the unknown categories tested
  int winner = -1;              // -1: no decision (features failed, e.g. too few points)
  std::vector<double> scores;   // per category, same order; empty without a decision
  std::vector<double> probabilities;  // the scores calibrated (Classification::probabilities); empty: none
  double novelty = std::numeric_limits<double>::quiet_NaN();  // NaN: the method has no novelty calibrated
  bool unknown = false;         // the model said "none of these" at its own operating point
};

struct Tally {
  size_t correct = 0;
  size_t total = 0;
  double percent() const { return total ? 100.0 * double(correct) / double(total) : 0.0; }
};

// Decisions of one stage and method, pooled over folds. A missing decision counts as wrong. Decisions
// on objects of no learnt category (truth < 0) are left out of every metric but the open-set ones.
Tally accuracy(std::span<const StageDecision> decisions, std::string_view stage, MethodId method);
// Mean over the categories of the per-category recall (each category weighs the same, whatever its
// number of views); categories without a decision of this stage and method are left out.
double balanced_accuracy(std::span<const StageDecision> decisions, std::string_view stage, MethodId method,
                         size_t categories);
// How far accuracy() could move with another draw of test objects: the percentile interval holding
// `level` of the accuracies of `draws` resamples of the tested objects, with replacement. An object is
// the unit, not a view: one object's views are right or wrong together far more often than apart. The
// same seed, the same interval. {0, 0} without decisions.
struct AccuracyInterval {
  double low = 0, high = 0;  // %
};
AccuracyInterval accuracy_interval(std::span<const StageDecision> decisions, std::string_view stage, MethodId method,
                                   double level = 0.95, size_t draws = 2000, uint64_t seed = 1);
// One view decided by two runs (the same object, view, stage and method, e.g. before and after a change
// or under two seeds' code): right in each. `unit`: what is resampled as one (an object, with its views).
struct PairedView {
  int unit = 0;
  bool right_before = false, right_after = false;
};
// Whether a change moved accuracy more than another draw of test objects could: each run's accuracy, the
// difference (after - before, points), and the percentile interval holding `level` of the differences of
// `draws` resamples of the units with replacement, both runs' views of a unit drawn together (paired).
// An interval that spans 0 is a change the tested objects cannot tell from none. Zeros without views.
struct PairedDifference {
  size_t views = 0, units = 0;
  double before = 0, after = 0, difference = 0;  // %, points
  AccuracyInterval interval;                     // of the difference, points
  size_t turned_right = 0, turned_wrong = 0;     // views wrong before and right after, and the reverse
};
PairedDifference paired_difference(std::span<const PairedView> views, double level = 0.95, size_t draws = 2000,
                                   uint64_t seed = 1);
// Rows: truth (query), columns: winner (result), percent of the row's decisions (missing ones are in
// the row's total but in no column, so such a row sums to less than 100).
std::vector<std::vector<double>> confusion_percent(std::span<const StageDecision> decisions, std::string_view stage,
                                                   MethodId method, size_t categories);

// Mann-Whitney AUROC: P(positive > negative), ties counting half; 0.5 when either side is empty.
double auroc(std::vector<double> negatives, std::vector<double> positives);

}  // namespace glimpse
