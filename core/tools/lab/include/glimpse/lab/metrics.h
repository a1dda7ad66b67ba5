// The lab's metrics beyond accuracy (learning/metrics.h): the category changes along the exploration of
// sec. 4, the open-set figures ("none of these") and how streamed decisions settle. Definitions in
// metrics.cpp, open_set.cpp and streams.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/learning/metrics.h"
#include "glimpse/learning/model.h"
#include "glimpse/views/exploration.h"

namespace glimpse {

// Number of times the decision changes along a sequence (a missing decision, -1, is a category too).
size_t category_changes(std::span<const int> winners);

// One test view's exploration: the decisions at the grid's keypoint stages, in order.
struct ExplorationTrace {
  int fold = 0, object = 0, view = 0;
  int truth = 0;
  int final_winner = -1;  // the decision on the full view
  std::vector<size_t> grid;             // keypoint counts
  std::vector<int> winners;             // decision at each
  std::vector<double> visible_fraction; // at each
  double full_visible_fraction = 0;
  bool correct() const { return final_winner == truth; }
};
// Traces of `method` from decisions whose stage is stage_name({kKeypoints, g}) for g in grid (plus
// "full" for the final decision); views without a full-view decision are skipped.
std::vector<ExplorationTrace> exploration_traces(std::span<const StageDecision> decisions, MethodId method,
                                                 const std::vector<size_t>& grid);

struct ChangeRow {
  size_t up_to_keypoints = 0;
  double mean_correct = 0, mean_incorrect = 0;  // mean changes over finally-correct / -incorrect views
  size_t views_correct = 0, views_incorrect = 0;
};
// Changes among the grid decisions at keypoint counts <= up_to, for each entry of up_to.
std::vector<ChangeRow> change_summary(const std::vector<ExplorationTrace>& traces,
                                      const std::vector<size_t>& up_to);

// ---- Open set: objects of no learnt category ("none of these") ------------------------------------

// A decision's novelty as the open-set metrics rank it: NaN (left out) when its method has none,
// +infinity when it was rejected for sure (features failed, or the method cannot judge the cloud).
double open_set_score(const StageDecision& d);

struct OpenSetRow {
  std::string stage;
  size_t known = 0, unknown = 0;           // decisions ranked (with a novelty)
  double auroc = 0.5;                      // P(an unknown view's novelty > a known view's), ties half
  double far_at_95 = 0;                    // % of unknown views accepted at the novelty accepting 95 % of
                                           // the tested known views (an oracle threshold: the test side's)
  double known_acceptance = 0;             // % of known views the models' own operating point accepts
  double false_acceptance = 0;             // % of unknown views it accepts (as some known category)
  double known_accuracy_closed = 0;        // % of known views right, "unknown" ignored (the closed set)
  double known_accuracy_open = 0;          // % of known views right and accepted
  double accepted_accuracy = 0;            // % right among the accepted known views
  std::vector<double> accepted_per_class;  // per unknown class: % of its views accepted
};
// One row per stage of `method`.
std::vector<OpenSetRow> open_set_summary(std::span<const StageDecision> decisions, const std::vector<Stage>& stages,
                                         MethodId method, size_t unknown_classes);

// ---- Streaming: when the decision settles (ScanSession, sec. 4) ----------------------------------------

// One test view streamed top to bottom through a ScanSession, one entry per chunk.
struct StreamTrace {
  int fold = 0, object = 0, view = 0;
  int truth = 0;                         // -1: an object of no learnt category
  int unknown_class = -1;                // then its index into EvalResult::unknown_categories
  std::vector<double> visible_fraction;  // accumulated points / full 3D cloud points
  std::vector<int> winners;              // report category index; -1 while the session cannot decide
  std::vector<double> confidence;
  std::vector<uint8_t> settled;          // the session's own flag
  std::vector<uint8_t> unknown;          // the session's "none of these" (winners keeps the nearest category)
  std::vector<double> novelty;           // the session's (smoothed) novelty of the winner; NaN: none
  std::vector<size_t> keypoints;
  std::vector<size_t> points;                    // accumulated after duplicate removal
  std::vector<std::vector<double>> raw_scores;   // per chunk, the chunk's own scores (report's category order)
};

// How early and how right settled decisions are: each view counts at its first settled chunk.
struct SettleRow {
  double threshold = -1;  // confidence threshold; -1: the session's own settled flag
  size_t views = 0, settled_views = 0, correct = 0;
  size_t unknown = 0;                 // settled as "none of these" (for a known view: counted wrong)
  double mean_visible_percent = 0;    // at the first settled chunk, over settled views
  double median_visible_percent = 0;
  double precision_percent() const { return settled_views ? 100.0 * double(correct) / double(settled_views) : 0.0; }
  double settled_percent() const { return views ? 100.0 * double(settled_views) / double(views) : 0.0; }
};
// The session's flags (threshold < 0), or "confidence >= threshold and, when keypoints matter, at
// least min_keypoints keypoints" recomputed from the recorded confidences: a calibration sweep.
// Views of learnt categories only; `truth_filter` >= 0 restricts to views of that category.
SettleRow settle_summary(const std::vector<StreamTrace>& traces, double threshold, size_t min_keypoints = 0,
                         int truth_filter = -1);
// Streams of objects of no learnt category (of `unknown_class` alone when >= 0), by the session's flags:
// right (`correct`) when the first settled decision is "unknown"; the rest settled on a category.
SettleRow unknown_settle_summary(const std::vector<StreamTrace>& traces, int unknown_class = -1);

}  // namespace glimpse
