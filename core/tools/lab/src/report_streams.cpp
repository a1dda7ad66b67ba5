// The report's sections on the exploration (sec. 4): how often the decision changes category as
// keypoints appear, and when a streamed decision settles (report.cpp puts them in order).
#include <algorithm>
#include <map>
#include <sstream>
#include <string>

#include "report_format.h"
#include "protocol.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/learning/model_internals.h"

namespace glimpse::eval_internal {

std::string changes_section(const EvalResult& r) {
  std::ostringstream o;
  static const std::map<size_t, std::pair<double, double>> kPaper = {{10, {0.41, 0.46}}, {25, {1.3, 1.6}}, {55, {2.8, 3.9}}};
  o << "## Category changes along the exploration (sec. 4)\n\n";
  o << "Method: **" << method_label(r.change_method) << "** (the recogniser's default, fixed before testing). For each test "
       "view, the decisions at keypoint counts ";
  for (size_t i = 0; i < r.grid.size(); ++i) o << (i ? ", " : "") << r.grid[i];
  o << "; a view is finally correct when its full-view decision is. A stage whose k exceeds the view's keypoints is the "
       "full view, so the sequence stops changing there.\n\n";
  o << "| up to | changes, finally correct | finally incorrect | views correct / incorrect | paper correct / incorrect |\n";
  o << "|---|---:|---:|---:|---:|\n";
  for (const ChangeRow& c : r.changes) {
    auto p = kPaper.find(c.up_to_keypoints);
    o << "| " << c.up_to_keypoints << " kp | " << fmt("%.2f", c.mean_correct) << " | " << fmt("%.2f", c.mean_incorrect)
      << " | " << c.views_correct << " / " << c.views_incorrect << " | "
      << (p != kPaper.end() ? fmt("%.2f", p->second.first) + " / " + fmt("%.2f", p->second.second) : "–") << " |\n";
  }
  o << "\nEvolution curves (decided category against visible % of the full cloud, one line per view, as the paper's "
       "Figures 5-6): [finally correct](evolution_correct.svg), [finally incorrect](evolution_incorrect.svg).\n\n";
  return o.str();
}

namespace {

// Every model has a settle probability and the sessions use it: decisions settle in probabilities.
bool settles_in_probability(const EvalResult& r) {
  const SessionParams& sp = r.params.session;
  return sp.settle_on_probability && sp.use_model_calibration && !r.settle_probabilities.empty() &&
         std::all_of(r.settle_probabilities.begin(), r.settle_probabilities.end(), [](double p) { return p > 0; });
}

// Where each model's streams settle, and how it was calibrated.
std::string settle_calibration_text(const EvalResult& r, bool in_probability) {
  std::ostringstream o;
  o << "Each model calibrated where its decisions settle on held-out folds of its own training objects ("
    << r.params.train.calibration_folds << " inner folds by object; nothing of the test views): "
    << (in_probability ? "the smallest probability of the winner (calibrated probabilities)"
                       : "the smallest margin between the best two scores")
    << " at which held-out decisions were " << pct(100 * r.params.train.settle_precision)
    << " % right; a category's confidence is that " << (in_probability ? "probability" : "margin over it")
    << " of the smoothed scores times the share of the last " << r.params.session.stability_window
    << " decisions its winner won. Settle " << (in_probability ? "probability" : "margin") << " per model:";
  const std::vector<double>& at = in_probability ? r.settle_probabilities : r.settle_margins;
  for (size_t i = 0; i < at.size(); ++i)
    o << (i ? "," : "") << " " << fmt("%.3f", at[i]) << " (held out " << pct(100 * r.calibration_accuracy[i], 1)
      << " % right)";
  o << ". The sweep below recomputes settling at fixed confidences from the recorded ones (without the session's "
       "hold rule), for comparison only.\n\n";
  return o.str();
}

}  // namespace

std::string streams_section(const EvalResult& r) {
  if (r.streams.empty()) return {};
  std::ostringstream o;
  const SessionParams& sp = r.params.session;
  const size_t min_kp = uses_keypoints(r.change_method) ? sp.min_keypoints : 0;
  o << "## Streaming: when the decision settles (ScanSession)\n\n";
  o << "Every view streamed top to bottom through a ScanSession of its fold's model (method **"
    << method_label(r.change_method) << "**), in chunks of " << pct(100 * r.params.stream_chunk_fraction, 1)
    << " % of the full 3D cloud's points. A view counts at its first settled decision: precision = share of those "
       "that name the true category, visible % = how much of the full cloud had been seen then. Goal: precision >= 95 % "
       "with settlement before 30 % visible on average.\n\n";
  if (r.settle_margins.empty())
    o << "| settled when | views settled | precision | mean visible % | median visible % |\n|---|---:|---:|---:|---:|\n";
  auto row = [&](const std::string& label, const SettleRow& s) {
    o << "| " << label << " | " << s.settled_views << " / " << s.views << " (" << pct(s.settled_percent(), 1) << " %) | "
      << pct(s.precision_percent(), 1) << " % | " << pct(s.mean_visible_percent, 1) << " | "
      << pct(s.median_visible_percent, 1) << " |\n";
  };
  const bool in_probability = settles_in_probability(r);
  if (!r.settle_margins.empty()) {
    o << settle_calibration_text(r, in_probability);
    o << "| settled when | views settled | precision | mean visible % | median visible % |\n|---|---:|---:|---:|---:|\n";
  }
  const SettleRow session = settle_summary(r.streams, -1);
  row("**session default** (" +
          (in_probability ? std::string("confidence >= the calibrated probability")
                          : "calibrated margin, confidence >= " + fmt("%.2f", sp.settle_confidence)) +
          ", the winner held " +
          std::to_string(sp.stability_window) + " chunks, the newest included, its novelty at most " +
          fmt("%.2f", sp.settle_novelty_share) + " x the threshold" +
          (session.unknown ? "; " + std::to_string(session.unknown) + " settled as unknown, counted wrong" : std::string()) + ")",
      session);
  for (double t : r.params.settle_sweep) row("confidence >= " + fmt("%.2f", t), settle_summary(r.streams, t, min_kp));
  o << "\nPer category, the session's own flag:\n\n| category | views settled | precision | mean visible % |\n"
       "|---|---:|---:|---:|\n";
  for (size_t c = 0; c < r.categories.size(); ++c) {
    const SettleRow s = settle_summary(r.streams, -1, 0, static_cast<int>(c));
    o << "| " << r.categories[c] << " | " << s.settled_views << " / " << s.views << " | " << pct(s.precision_percent(), 1)
      << " % | " << pct(s.mean_visible_percent, 1) << " |\n";
  }
  const SettleRow unknown = unknown_settle_summary(r.streams);
  if (unknown.views) {
    o << "\nObjects of no learnt category, streamed the same way (right: the first settled decision is \"unknown\"; a "
         "known category settled on counts wrong): "
      << unknown.settled_views << " of " << unknown.views << " views settled (" << pct(unknown.settled_percent(), 1) << " %), "
      << unknown.correct << " as unknown (" << pct(unknown.precision_percent(), 1) << " % of those settled), at "
      << pct(unknown.mean_visible_percent, 1) << " % visible on average. \"Unknown\" settles once each of the last "
      << unknown_settle_chunks(sp) << " decisions was unknown, the newest chunk's own novelty "
         "above the threshold, with confidence >= " << fmt("%.2f", sp.unknown_settle_confidence) << " (a smoothed novelty "
      << fmt("%.2f", 1 + sp.unknown_settle_confidence * sp.unknown_full_excess) << " x the threshold).\n\n| class | views settled | settled unknown | mean visible % |\n|---|---:|---:|---:|\n";
    for (size_t c = 0; c < r.unknown_categories.size(); ++c) {
      const SettleRow s = unknown_settle_summary(r.streams, static_cast<int>(c));
      if (s.views)
        o << "| " << r.unknown_categories[c] << " | " << s.settled_views << " / " << s.views << " | " << pct(s.precision_percent(), 1)
          << " % | " << pct(s.mean_visible_percent, 1) << " |\n";
    }
  }
  size_t final_correct = 0, decided = 0;
  for (const StreamTrace& t : r.streams)
    if (!t.winners.empty() && t.truth >= 0) ++decided, final_correct += t.winners.back() == t.truth;
  o << "\nLast decision of each stream (the whole view seen): " << final_correct << " / " << decided << " correct ("
    << pct(decided ? 100.0 * double(final_correct) / double(decided) : 0, 1) << " %). Every chunk is in "
    << "[streams.csv](streams.csv).\n\n";
  return o.str();
}

}  // namespace glimpse::eval_internal
