// The evaluation's other outputs: a CSV of every decision and of every streamed chunk, SVG evolution
// curves like the paper's Figures 5-6 (hand-written SVG, no dependencies), a terminal summary, and the
// report folder that holds them with report.md.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "report_format.h"

namespace glimpse {

using namespace eval_internal;

std::string streams_csv(const EvalResult& r) {
  std::ostringstream o;
  o << "fold,object,view,truth,chunk,visible_fraction,winner,confidence,settled,keypoints,points";
  for (const std::string& c : r.categories) o << ",raw_" << c;
  o << ",unknown,novelty\n";
  for (const StreamTrace& t : r.streams)
    for (size_t i = 0; i < t.winners.size(); ++i) {
      o << t.fold << "," << r.object_ids[static_cast<size_t>(t.object)] << "," << t.view << ","
        << (t.truth >= 0 ? r.categories[static_cast<size_t>(t.truth)] : "unknown:" + r.unknown_categories[static_cast<size_t>(t.unknown_class)]) << "," << i << "," << fmt("%.4f", t.visible_fraction[i]) << ","
        << (t.winners[i] >= 0 ? r.categories[static_cast<size_t>(t.winners[i])] : std::string()) << ","
        << fmt("%.4f", t.confidence[i]) << "," << int(t.settled[i]) << "," << t.keypoints[i] << ","
        << (i < t.points.size() ? t.points[i] : 0);
      for (size_t c = 0; c < r.categories.size(); ++c)
        o << "," << (i < t.raw_scores.size() && c < t.raw_scores[i].size() ? fmt("%.4f", t.raw_scores[i][c]) : "");
      o << "," << (i < t.unknown.size() ? int(t.unknown[i]) : 0) << ","
        << (i < t.novelty.size() && std::isfinite(t.novelty[i]) ? fmt("%.4f", t.novelty[i]) : std::string()) << "\n";
    }
  return o.str();
}

std::string decisions_csv(const EvalResult& r) {
  std::ostringstream o;
  o << "fold,object,view,stage,method,visible_fraction,points,keypoints,truth,winner";
  for (const std::string& c : r.categories) o << ",score_" << c;
  o << ",novelty,unknown";
  for (const std::string& c : r.categories) o << ",probability_" << c;
  o << "\n";
  for (const StageDecision& d : r.decisions) {
    o << d.fold << "," << r.object_ids[d.object] << "," << d.view << "," << d.stage << "," << method_name(d.method) << ","
      << fmt("%.4f", d.visible_fraction) << "," << d.points << "," << d.keypoints << ","
      << (d.truth >= 0 ? r.categories[static_cast<size_t>(d.truth)] : "unknown:" + r.unknown_categories[static_cast<size_t>(d.unknown_class)]) << ","
      << (d.winner >= 0 ? r.categories[d.winner] : std::string("none"));
    for (size_t c = 0; c < r.categories.size(); ++c)
      o << "," << (c < d.scores.size() ? fmt("%.4f", d.scores[c]) : std::string());
    o << "," << (std::isfinite(d.novelty) ? fmt("%.4f", d.novelty) : std::string()) << "," << (d.unknown ? 1 : 0);
    for (size_t c = 0; c < r.categories.size(); ++c)
      o << "," << (c < d.probabilities.size() ? fmt("%.4f", d.probabilities[c]) : std::string());
    o << "\n";
  }
  return o.str();
}

std::string evolution_svg(const std::vector<ExplorationTrace>& traces, const std::vector<std::string>& categories,
                          bool correct, std::string_view title) {
  const double panel_w = 760, panel_h = 150, left = 170, top = 50, gap = 40, right = 30;
  const size_t n_cat = std::max<size_t>(1, categories.size());
  const double width = left + panel_w + right, height = top + double(n_cat) * (panel_h + gap) + 20;
  double x_max = 10;
  for (const ExplorationTrace& t : traces)
    if (t.correct() == correct) x_max = std::max(x_max, 100 * t.full_visible_fraction);
  x_max = 10 * std::ceil(x_max / 10);

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << width / 2 << "\" y=\"24\" text-anchor=\"middle\" font-size=\"16\">" << xml_escape(title) << "</text>\n";
  for (size_t q = 0; q < categories.size(); ++q) {
    const double y0 = top + double(q) * (panel_h + gap);
    auto y_of = [&](double level) { return y0 + panel_h * (double(n_cat) - level - 0.5) / double(n_cat); };
    auto x_of = [&](double percent) { return left + panel_w * percent / x_max; };
    size_t shown = 0;
    for (const ExplorationTrace& t : traces) shown += t.truth == int(q) && t.correct() == correct;
    o << "<g>\n<rect x=\"" << left << "\" y=\"" << y0 << "\" width=\"" << panel_w << "\" height=\"" << panel_h
      << "\" fill=\"none\" stroke=\"#888\"/>\n";
    o << "<text x=\"" << left << "\" y=\"" << y0 - 6 << "\" font-weight=\"bold\">true category: " << xml_escape(categories[q])
      << " (" << shown << " views)</text>\n";
    for (size_t c = 0; c < categories.size(); ++c)
      o << "<text x=\"" << left - 8 << "\" y=\"" << y_of(double(c)) + 4 << "\" text-anchor=\"end\""
        << (c == q ? " font-weight=\"bold\"" : "") << ">" << xml_escape(categories[c]) << "</text>\n"
        << "<line x1=\"" << left << "\" x2=\"" << left + panel_w << "\" y1=\"" << y_of(double(c)) << "\" y2=\""
        << y_of(double(c)) << "\" stroke=\"#eee\"/>\n";
    for (double x = 0; x <= x_max + 1e-9; x += 10)
      o << "<text x=\"" << x_of(x) << "\" y=\"" << y0 + panel_h + 14 << "\" text-anchor=\"middle\">" << x << "</text>\n";
    size_t k = 0;
    for (const ExplorationTrace& t : traces) {
      if (t.truth != int(q) || t.correct() != correct) continue;
      // Jitter each view's line within its band so overlapping decisions stay distinguishable.
      const double jitter = shown > 1 ? 0.6 * (double(k) / double(shown - 1) - 0.5) : 0.0;
      const int hue = int((k * 137) % 360);
      ++k;
      std::string pts;
      auto add = [&](double vis, int winner) {
        if (winner < 0) return;
        pts += fmt("%.1f", x_of(100 * vis)) + "," + fmt("%.1f", y_of(double(winner) + jitter)) + " ";
      };
      for (size_t g = 0; g < t.grid.size(); ++g) add(t.visible_fraction[g], t.winners[g]);
      add(t.full_visible_fraction, t.final_winner);
      o << "<polyline fill=\"none\" stroke=\"hsl(" << hue << ",70%,40%)\" stroke-opacity=\"0.7\" points=\"" << pts
        << "\"><title>" << "object " << t.object << " view " << t.view << "</title></polyline>\n";
    }
    o << "</g>\n";
  }
  o << "<text x=\"" << left + panel_w / 2 << "\" y=\"" << height - 4
    << "\" text-anchor=\"middle\">visible part of the full 3D cloud (%)</text>\n";
  o << "</svg>\n";
  return o.str();
}

bool tests_learnt_objects(const EvalResult& r) {
  if (!r.cross_source) return false;
  for (const std::string& x : r.test_sources)
    if (std::find(r.train_sources.begin(), r.train_sources.end(), x) != r.train_sources.end()) return true;
  return false;
}

std::string summary_table(const EvalResult& r) {
  const std::vector<std::string> stages = main_stage_names(r);
  std::ostringstream o;
  o << "method  ";
  for (const std::string& s : stages) o << std::string(std::max<int>(1, 14 - int(s.size())), ' ') << s;
  o << "\n";
  for (MethodId m : r.params.methods) {
    std::string name = method_label(m);
    o << name << std::string(std::max<int>(1, 8 - int(name.size())), ' ');
    for (const std::string& s : stages) {
      std::string cell = pct(accuracy(r.decisions, s, m).percent(), 1);
      const double paper = paper_accuracy(m, s);
      if (!std::isnan(paper)) cell += " (" + pct(paper) + ")";
      o << std::string(std::max<int>(1, 14 - int(cell.size())), ' ') << cell;
    }
    o << "\n";
  }
  o << "visible%";
  for (const std::string& s : stages) {
    const StageStats* st = stats_of(r, s);
    const std::string cell = st ? pct(st->mean_visible_percent, 1) : "-";
    o << std::string(std::max<int>(1, 14 - int(cell.size())), ' ') << cell;
  }
  o << "\n";
  return o.str();
}

Status write_report(const EvalResult& r, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return invalid_argument("cannot create " + dir + ": " + ec.message());
  auto write = [&](const std::string& name, const std::string& text) -> Status {
    const std::string path = (std::filesystem::path(dir) / name).string();
    std::ofstream f(path, std::ios::binary);
    f << text;
    f.close();
    if (!f) return internal_error("cannot write " + path);
    return {};
  };
  const char* kFiles[] = {"report.md", "decisions.csv", "evolution_correct.svg", "evolution_incorrect.svg", "streams.csv",
                          "reliability.svg"};
  const std::string method = method_label(r.change_method);
  const std::string texts[] = {
      markdown_report(r), decisions_csv(r),
      evolution_svg(r.traces, r.categories, true, "Finally correct views: decided category along the exploration (" + method + ")"),
      evolution_svg(r.traces, r.categories, false, "Finally incorrect views: decided category along the exploration (" + method + ")"),
      streams_csv(r), reliability_svg(r)};
  for (size_t i = 0; i < std::size(kFiles); ++i)
    if (Status s = write(kFiles[i], texts[i]); !s.ok()) return s;
  return {};
}

}  // namespace glimpse
