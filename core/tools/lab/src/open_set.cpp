// The open set ("none of these"): how well novelty tells views of categories no model learnt from the
// known ones, per stage, and what the models' own operating point accepts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "glimpse/lab/evaluation.h"

namespace glimpse {

namespace {

std::string fixed(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

double percent(size_t part, size_t whole) { return whole ? 100.0 * double(part) / double(whole) : 0.0; }

// The novelty accepting `share` of `known` (sorted ascending): the smallest at or above that share.
double accepting(const std::vector<double>& known, double share) {
  if (known.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t rank = static_cast<size_t>(std::ceil(share * double(known.size()) - 1e-9));
  return known[std::min(known.size() - 1, rank > 0 ? rank - 1 : 0)];
}

}  // namespace

double open_set_score(const StageDecision& d) {
  if (d.winner < 0 || (d.unknown && !std::isfinite(d.novelty))) return std::numeric_limits<double>::infinity();
  return d.novelty;  // NaN when the method has no novelty
}

std::vector<OpenSetRow> open_set_summary(std::span<const StageDecision> decisions, const std::vector<Stage>& stages,
                                         MethodId method, size_t unknown_classes) {
  std::vector<OpenSetRow> rows;
  for (const Stage& stage : stages) {
    OpenSetRow row;
    row.stage = stage_name(stage);
    std::vector<double> known, unknown;
    size_t known_total = 0, known_accepted = 0, right = 0, right_accepted = 0, unknown_total = 0, unknown_accepted = 0;
    std::vector<size_t> per_total(unknown_classes, 0), per_accepted(unknown_classes, 0);
    for (const StageDecision& d : decisions) {
      if (d.method != method || d.stage != row.stage) continue;
      const bool accepted = d.winner >= 0 && !d.unknown;
      const double score = open_set_score(d);
      if (d.truth >= 0) {
        ++known_total;
        known_accepted += accepted;
        right += d.winner == d.truth;
        right_accepted += accepted && d.winner == d.truth;
        if (!std::isnan(score)) known.push_back(score);
        continue;
      }
      ++unknown_total;
      unknown_accepted += accepted;
      if (d.unknown_class >= 0 && static_cast<size_t>(d.unknown_class) < unknown_classes) {
        ++per_total[static_cast<size_t>(d.unknown_class)];
        per_accepted[static_cast<size_t>(d.unknown_class)] += accepted;
      }
      if (!std::isnan(score)) unknown.push_back(score);
    }
    row.known = known.size(), row.unknown = unknown.size();
    row.auroc = auroc(known, unknown);
    std::sort(known.begin(), known.end());
    const double t95 = accepting(known, 0.95);
    row.far_at_95 = percent(static_cast<size_t>(std::count_if(unknown.begin(), unknown.end(),
                                                              [&](double u) { return u <= t95; })),
                            unknown.size());
    row.known_acceptance = percent(known_accepted, known_total);
    row.false_acceptance = percent(unknown_accepted, unknown_total);
    row.known_accuracy_closed = percent(right, known_total);
    row.known_accuracy_open = percent(right_accepted, known_total);
    row.accepted_accuracy = percent(right_accepted, known_accepted);
    for (size_t c = 0; c < unknown_classes; ++c) row.accepted_per_class.push_back(percent(per_accepted[c], per_total[c]));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string open_set_section(const EvalResult& r) {
  if (r.unknown_categories.empty()) return {};
  const std::vector<OpenSetRow> rows =
      open_set_summary(r.decisions, r.params.stages, r.change_method, r.unknown_categories.size());
  size_t objects = 0;
  for (int c : r.object_unknown_class) objects += c >= 0;
  std::string classes;
  for (const std::string& c : r.unknown_categories) classes += (classes.empty() ? "" : ", ") + c;
  double lo = INFINITY, hi = -INFINITY;
  for (double t : r.novelty_thresholds)
    if (std::isfinite(t)) lo = std::min(lo, t), hi = std::max(hi, t);
  std::ostringstream o;
  o << "## Open set: objects of no learnt category (\"none of these\")\n\n";
  o << "Every view of " << objects << " objects of " << r.unknown_categories.size()
    << " categories no model learns (" << classes << ") is tested too, "
    << (r.cross_source ? "by the one model" : "each object by one fold's model") << ", with "
    << method_name(r.change_method) << ". A model knows nothing of them: its novelty (per component, the "
    << "distance to the decided category, the mean over its (up to) " << r.params.train.novelty_objects
    << " nearest training objects of the distance to each one's nearest reference, over the typical held-out "
    << "distance for that category and kind of reference, a whole view or a top-down prefix, plus what the "
    << "stage's PCA leaves out over its typical value; averaged over the components and divided by the decision's score "
    << "for the category"
    << (r.params.train.novelty_prefix > 0
            ? "; per category, the geometric mean of the cloud's and its top-down prefix's, the highest " +
                  fixed("%.0f", 100 * r.params.train.novelty_prefix) + " % of its points (of at most " +
                  std::to_string(r.params.train.novelty_prefix_points) + "), when that keeps " +
                  std::to_string(r.params.train.novelty_prefix_min_points) + " or more"
            : std::string())
    << ") was calibrated on held-out folds of its own training set"
    << (r.novelty_models ? " (of " + std::to_string(r.novelty_models) + " of the " + std::to_string(r.novelty_thresholds.size()) +
                               " models, by a model of its training views not augmented: the simulated sensors' views and "
                               "the zoo beside other sources are learnt by the decision, not measured against)"
                         : std::string())
    << ", and its operating point accepts "
    << fixed("%.0f", 100 * r.params.train.known_acceptance) << " % of those held-out known decisions";
  if (std::isfinite(lo)) o << " (novelty threshold " << fixed("%.2f", lo) << (hi > lo ? "–" + fixed("%.2f", hi) : "") << ")";
  o << ". AUROC ranks known against unknown views by novelty; FAR at 95 % is the share of unknown views "
    << "accepted at the novelty that accepts 95 % of the tested known views (the test side's threshold, "
    << "for comparison with other work); the other columns are at the models' own operating point. Known "
    << "accuracy: closed set (\"unknown\" ignored), right and accepted (a rejected known view counts as "
    << "wrong), and right among the accepted.\n\n";
  o << "| stage | AUROC | FAR at 95 % | known accepted | unknown accepted | known accuracy closed | right and "
       "accepted | right among accepted | known / unknown views |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const OpenSetRow& row : rows)
    o << "| " << row.stage << " | " << fixed("%.3f", row.auroc) << " | " << fixed("%.1f", row.far_at_95) << " | "
      << fixed("%.1f", row.known_acceptance) << " | " << fixed("%.1f", row.false_acceptance) << " | "
      << fixed("%.1f", row.known_accuracy_closed) << " | " << fixed("%.1f", row.known_accuracy_open) << " | "
      << fixed("%.1f", row.accepted_accuracy) << " | " << row.known << " / " << row.unknown << " |\n";
  o << "\nAccepted (as some known category) at the operating point, % of each unknown class's views:\n\n| class |";
  for (const OpenSetRow& row : rows) o << " " << row.stage << " |";
  o << "\n|---|";
  for (size_t i = 0; i < rows.size(); ++i) o << "---:|";
  o << "\n";
  for (size_t c = 0; c < r.unknown_categories.size(); ++c) {
    o << "| " << r.unknown_categories[c] << " |";
    for (const OpenSetRow& row : rows) o << " " << fixed("%.0f", row.accepted_per_class[c]) << " |";
    o << "\n";
  }
  o << "\n";
  return o.str();
}

}  // namespace glimpse
