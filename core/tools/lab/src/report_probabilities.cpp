// The report's calibrated probabilities: how well the default method's raw scores and its probabilities
// keep their word on the known test views, per main stage, and the reliability diagram.
#include <sstream>

#include "glimpse/learning/probabilities.h"
#include "report_format.h"

namespace glimpse {

using eval_internal::fmt;
using eval_internal::main_stage_names;
using eval_internal::method_label;
using eval_internal::xml_escape;

namespace {

constexpr size_t kBins = 10;

// The known test views of one stage by the default method: the raw scores, the probabilities and truths
// (only views whose decision has probabilities).
struct StageProbabilities {
  std::vector<std::vector<double>> scores, probabilities;
  std::vector<int> truths;
};

StageProbabilities stage_probabilities(const EvalResult& r, const std::string& stage) {
  StageProbabilities out;
  for (const StageDecision& d : r.decisions) {
    if (d.method != r.change_method || d.stage != stage || d.truth < 0 || d.probabilities.empty()) continue;
    out.scores.push_back(d.scores);
    out.probabilities.push_back(d.probabilities);
    out.truths.push_back(d.truth);
  }
  return out;
}

double mean_top(const std::vector<std::vector<double>>& rows) {
  double sum = 0;
  for (const std::vector<double>& p : rows) sum += *std::max_element(p.begin(), p.end());
  return rows.empty() ? 0 : sum / double(rows.size());
}

}  // namespace

std::string probabilities_section(const EvalResult& r) {
  std::ostringstream o;
  bool any = false;
  for (const std::string& stage : main_stage_names(r)) any = any || !stage_probabilities(r, stage).truths.empty();
  if (!any) return {};
  o << "## Calibrated probabilities (" << method_label(r.change_method) << ")\n\n";
  o << "Each model turns its scores into probabilities with one temperature, the one whose probabilities give its "
       "held-out training decisions (inner folds of its own training objects) the least log loss; temperature per model:";
  for (size_t i = 0; i < r.probability_temperatures.size(); ++i)
    o << (i ? "," : "") << " " << fmt("%.3f", r.probability_temperatures[i]);
  o << ". Known test views" << (r.cross_source ? " of collections no model learnt or calibrated on" : "")
    << "; expected calibration error (ECE) over " << kBins
    << " equal bins of the winner's probability, mean log loss and Brier score, of the raw scores -> of the "
       "probabilities. [Reliability diagram](reliability.svg).\n\n";
  o << "| stage | views | right % | mean top score | mean top probability | ECE | log loss | Brier |\n"
       "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const std::string& stage : main_stage_names(r)) {
    const StageProbabilities s = stage_probabilities(r, stage);
    if (s.truths.empty()) continue;
    const ProbabilityQuality raw = probability_quality(s.scores, s.truths, kBins);
    const ProbabilityQuality cal = probability_quality(s.probabilities, s.truths, kBins);
    size_t right = 0;
    for (const ReliabilityBin& b : cal.bins) right += static_cast<size_t>(std::lround(b.accuracy * double(b.decisions)));
    o << "| " << stage << " | " << cal.decisions << " | " << fmt("%.1f", 100.0 * double(right) / double(cal.decisions))
      << " | " << fmt("%.3f", mean_top(s.scores)) << " | " << fmt("%.3f", mean_top(s.probabilities)) << " | "
      << fmt("%.3f", raw.expected_calibration_error) << " -> **" << fmt("%.3f", cal.expected_calibration_error) << "** | "
      << fmt("%.3f", raw.log_loss) << " -> " << fmt("%.3f", cal.log_loss) << " | " << fmt("%.3f", raw.brier) << " -> "
      << fmt("%.3f", cal.brier) << " |\n";
  }
  o << "\n";
  return o.str();
}

std::string reliability_svg(const EvalResult& r) {
  const std::vector<std::string> stages = main_stage_names(r);
  const double side = 260, left = 60, top = 60, gap = 60, bottom = 60;
  const double width = left + double(stages.size()) * (side + gap), height = top + side + bottom;
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fmt("%.0f", width) << "\" height=\"" << fmt("%.0f", height)
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << left << "\" y=\"24\" font-size=\"15\">"
    << xml_escape("Reliability: share right against the winner's probability (" + method_label(r.change_method) +
                  "; grey: raw scores, blue: calibrated probabilities)")
    << "</text>\n";
  for (size_t i = 0; i < stages.size(); ++i) {
    const double x0 = left + double(i) * (side + gap), y0 = top + side;
    const auto X = [&](double v) { return fmt("%.1f", x0 + v * side); };
    const auto Y = [&](double v) { return fmt("%.1f", y0 - v * side); };
    o << "<g>\n<rect x=\"" << X(0) << "\" y=\"" << Y(1) << "\" width=\"" << side << "\" height=\"" << side
      << "\" fill=\"none\" stroke=\"#888\"/>\n";
    o << "<line x1=\"" << X(0) << "\" y1=\"" << Y(0) << "\" x2=\"" << X(1) << "\" y2=\"" << Y(1)
      << "\" stroke=\"#bbb\" stroke-dasharray=\"4 3\"/>\n";
    o << "<text x=\"" << X(0) << "\" y=\"" << fmt("%.1f", y0 - side - 8) << "\">" << xml_escape(stages[i]) << "</text>\n";
    o << "<text x=\"" << X(0.3) << "\" y=\"" << fmt("%.1f", y0 + 30) << "\">winner's probability</text>\n";
    if (i == 0)
      o << "<text x=\"" << fmt("%.1f", x0 - 30) << "\" y=\"" << Y(0.4) << "\" transform=\"rotate(-90 " << fmt("%.1f", x0 - 30)
        << " " << Y(0.4) << ")\">share right</text>\n";
    for (double t : {0.0, 0.5, 1.0}) {
      o << "<text x=\"" << X(t) << "\" y=\"" << fmt("%.1f", y0 + 14) << "\" text-anchor=\"middle\">" << fmt("%g", t) << "</text>\n";
      o << "<text x=\"" << fmt("%.1f", x0 - 6) << "\" y=\"" << Y(t) << "\" text-anchor=\"end\" dy=\"4\">" << fmt("%g", t)
        << "</text>\n";
    }
    const StageProbabilities s = stage_probabilities(r, stages[i]);
    const std::pair<const std::vector<std::vector<double>>*, const char*> series[] = {{&s.scores, "#999"}, {&s.probabilities, "#1f5fbf"}};
    for (const auto& [rows, colour] : series) {
      const ProbabilityQuality q = probability_quality(*rows, s.truths, kBins);
      std::string points;
      for (const ReliabilityBin& b : q.bins) {
        if (!b.decisions) continue;
        points += X(b.mean_probability) + "," + Y(b.accuracy) + " ";
        o << "<circle class=\"bin\" cx=\"" << X(b.mean_probability) << "\" cy=\"" << Y(b.accuracy) << "\" r=\"3\" fill=\"" << colour
          << "\"><title>" << b.decisions << " views</title></circle>\n";
      }
      if (!points.empty()) o << "<polyline points=\"" << points << "\" fill=\"none\" stroke=\"" << colour << "\"/>\n";
    }
    o << "</g>\n";
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace glimpse
