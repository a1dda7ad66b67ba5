// Streaming metrics of the evaluation: how early and how right the ScanSession's settled decisions are.
#include <algorithm>

#include "glimpse/lab/evaluation.h"

namespace glimpse {

namespace {
// Each view `counts` counts at its first settled chunk, right when `right` says so.
template <class Counts, class Right>
SettleRow first_settled(const std::vector<StreamTrace>& traces, double threshold, size_t min_keypoints, Counts counts,
                        Right right) {
  SettleRow row;
  row.threshold = threshold;
  std::vector<double> visible;
  for (const StreamTrace& t : traces) {
    if (!counts(t)) continue;
    ++row.views;
    for (size_t i = 0; i < t.winners.size(); ++i) {
      const bool settled = threshold < 0 ? t.settled[i] != 0
                                         : t.winners[i] >= 0 && t.confidence[i] >= threshold &&
                                               t.keypoints[i] >= min_keypoints;
      if (!settled) continue;
      ++row.settled_views;
      // The sweep reads scores only: there nothing settles "unknown".
      const bool unknown = threshold < 0 && i < t.unknown.size() && t.unknown[i];
      row.correct += right(t, i, unknown);
      row.unknown += unknown;
      visible.push_back(100.0 * t.visible_fraction[i]);
      break;
    }
  }
  if (!visible.empty()) {
    for (double v : visible) row.mean_visible_percent += v;
    row.mean_visible_percent /= double(visible.size());
    std::sort(visible.begin(), visible.end());
    row.median_visible_percent = visible[visible.size() / 2];
  }
  return row;
}
}  // namespace

SettleRow settle_summary(const std::vector<StreamTrace>& traces, double threshold, size_t min_keypoints,
                         int truth_filter) {
  // A known view the session settles as "unknown" is answered wrongly.
  return first_settled(
      traces, threshold, min_keypoints, [&](const StreamTrace& t) { return t.truth >= 0 && (truth_filter < 0 || t.truth == truth_filter); },
      [](const StreamTrace& t, size_t i, bool unknown) { return !unknown && t.winners[i] == t.truth; });
}

SettleRow unknown_settle_summary(const std::vector<StreamTrace>& traces, int unknown_class) {
  return first_settled(
      traces, -1, 0, [&](const StreamTrace& t) { return t.truth < 0 && (unknown_class < 0 || t.unknown_class == unknown_class); },
      [](const StreamTrace&, size_t, bool unknown) { return unknown; });
}

}  // namespace glimpse
