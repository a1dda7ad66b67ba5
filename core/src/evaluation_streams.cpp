// Streaming metrics of the evaluation: how early and how right the ScanSession's settled decisions are.
#include <algorithm>

#include "glimpse/evaluation.h"

namespace glimpse {

SettleRow settle_summary(const std::vector<StreamTrace>& traces, double threshold, size_t min_keypoints,
                         int truth_filter) {
  SettleRow row;
  row.threshold = threshold;
  std::vector<double> visible;
  for (const StreamTrace& t : traces) {
    if (truth_filter >= 0 && t.truth != truth_filter) continue;
    ++row.views;
    for (size_t i = 0; i < t.winners.size(); ++i) {
      const bool settled = threshold < 0 ? t.settled[i] != 0
                                         : t.winners[i] >= 0 && t.confidence[i] >= threshold &&
                                               t.keypoints[i] >= min_keypoints;
      if (!settled) continue;
      ++row.settled_views;
      // A known view the session settles as "unknown" is answered wrongly (the sweep reads scores only).
      const bool unknown = threshold < 0 && i < t.unknown.size() && t.unknown[i];
      row.correct += !unknown && t.winners[i] == t.truth;
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

}  // namespace glimpse
