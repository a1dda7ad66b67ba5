#include "client/evaluate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "client/render.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/views/exploration.h"

namespace glimpse::client {
namespace {

// The views decided wrongly (or not at all) at `stage`, grouped by object in report order.
std::map<int, std::vector<const StageDecision*>> Misclassified(const EvaluationReport& r, const std::string& stage) {
  std::map<int, std::vector<const StageDecision*>> out;
  for (const StageDecision& d : r.decisions)
    if (d.stage == stage && d.winner != d.truth) out[d.object].push_back(&d);
  return out;
}

std::string Decided(const EvaluationReport& r, const StageDecision& d) {
  if (d.winner < 0) return "no answer";
  const double score = static_cast<size_t>(d.winner) < d.scores.size() ? d.scores[static_cast<size_t>(d.winner)] : 0.0;
  return r.categories[static_cast<size_t>(d.winner)] + " (" + Fixed(score, 2) + ")";
}

}  // namespace

Expected<std::vector<Stage>> ParseStages(std::string_view text) {
  std::vector<Stage> out;
  size_t begin = 0;
  while (begin <= text.size()) {
    size_t end = text.find(',', begin);
    if (end == std::string_view::npos) end = text.size();
    std::string item(text.substr(begin, end - begin));
    begin = end + 1;
    item.erase(std::remove(item.begin(), item.end(), ' '), item.end());
    if (item.empty()) continue;
    Stage stage;
    if (item == "full") {
      stage = {StageKind::kFull, 0};
    } else {
      if (item.back() == '%') item.pop_back();
      char* rest = nullptr;
      const double percent = std::strtod(item.c_str(), &rest);
      if (item.empty() || *rest || !(percent > 0 && percent <= 100))
        return invalid_argument("stage '" + item + "': want 'full' or a percentage in (0, 100] of the object's cloud");
      stage = {StageKind::kFraction, percent / 100.0};
    }
    if (std::find(out.begin(), out.end(), stage) == out.end()) out.push_back(stage);
  }
  if (out.empty()) return invalid_argument("no stages: want e.g. full,10,20");
  return out;
}

Cloud StageCloud(const Cloud& view, size_t full_points, const Stage& stage) {
  if (stage.kind != StageKind::kFraction) return view;
  return reveal_top_down(view, fraction_prefix(view.points.size(), full_points, stage.value));
}

std::vector<std::string> ReportCategories(const std::vector<std::string>& model_categories,
                                          const std::vector<std::string>& folder_categories) {
  std::vector<std::string> out = model_categories;
  std::set<std::string> others;
  for (const std::string& c : folder_categories)
    if (std::find(out.begin(), out.end(), c) == out.end()) others.insert(c);
  out.insert(out.end(), others.begin(), others.end());
  return out;
}

namespace {
// The stage's known views that got probabilities: how well those keep their word (none: 0 decisions).
ProbabilityQuality StageProbabilityQuality(const EvaluationReport& r, const std::string& stage) {
  std::vector<std::vector<double>> probabilities;
  std::vector<int> truths;
  for (const StageDecision& d : r.decisions)
    if (d.stage == stage && d.method == r.method_id && !d.probabilities.empty())
      probabilities.push_back(d.probabilities), truths.push_back(d.truth);
  return probability_quality(probabilities, truths);
}

std::string CalibrationErrorJson(const ProbabilityQuality& q) {
  return q.decisions ? JsonNumber(q.expected_calibration_error) : "null";
}
}  // namespace

std::string EvaluationText(const EvaluationReport& r) {
  const size_t views = r.objects.size() * r.views_per_object;
  std::string out = "model " + r.model + ", method " + r.method + ": " + std::to_string(r.objects.size()) +
                    " objects of " + r.folder + ", " + std::to_string(r.views_per_object) + " views each (" +
                    std::to_string(views) + " views), " + Fixed(r.seconds, 1) + " s\n";
  std::vector<std::vector<std::string>> table = {{"stage", "accuracy", "balanced", "right/views", "calibration error"}};
  for (const Stage& s : r.stages) {
    const std::string name = stage_name(s);
    const Tally t = accuracy(r.decisions, name, r.method_id);
    const double balanced = balanced_accuracy(r.decisions, name, r.method_id, r.categories.size());
    const ProbabilityQuality q = StageProbabilityQuality(r, name);
    table.push_back({name, Fixed(t.percent(), 1) + " %", Fixed(balanced, 1) + " %",
                     std::to_string(t.correct) + "/" + std::to_string(t.total),
                     q.decisions ? Fixed(q.expected_calibration_error, 3) : "-"});
  }
  out += Table(table);
  for (size_t c = r.model_categories; c < r.categories.size(); ++c)
    out += "note: the model does not know '" + r.categories[c] + "': its views count as wrong\n";

  const std::string first = stage_name(r.stages.front());
  const auto confusion = confusion_percent(r.decisions, first, r.method_id, r.categories.size());
  out += "\nconfusion at " + first + ", % of each true category's views (rows: truth, columns: decided):\n";
  std::vector<std::vector<std::string>> rows = {{""}};
  for (size_t c = 0; c < r.model_categories; ++c) rows[0].push_back(r.categories[c]);
  for (size_t t = 0; t < r.categories.size(); ++t) {
    if (std::find(r.object_truth.begin(), r.object_truth.end(), int(t)) == r.object_truth.end()) continue;
    std::vector<std::string> row = {r.categories[t]};
    for (size_t c = 0; c < r.model_categories; ++c) row.push_back(Fixed(confusion[t][c], 1));
    rows.push_back(std::move(row));
  }
  out += Table(rows);

  const auto wrong = Misclassified(r, first);
  size_t wrong_views = 0;
  for (const auto& [object, list] : wrong) wrong_views += list.size();
  auto count = [](size_t n, const char* noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); };
  out += "\nmisclassified at " + first + ": " + count(wrong_views, "view") + " of " + count(wrong.size(), "object") + "\n";
  std::vector<std::vector<std::string>> listing;
  for (const auto& [object, list] : wrong) {
    std::vector<std::string> parts;
    for (const StageDecision* d : list) parts.push_back("view " + std::to_string(d->view) + " -> " + Decided(r, *d));
    listing.push_back({"  " + r.objects[static_cast<size_t>(object)], Joined(parts, ", ")});
  }
  out += Table(listing);
  if (!r.failures.empty()) {
    out += "\n" + std::to_string(r.failures.size()) + " clouds got no answer (counted as wrong):\n";
    for (const EvaluationReport::Failure& f : r.failures)
      out += "  " + r.objects[static_cast<size_t>(f.object)] + (f.view >= 0 ? " view " + std::to_string(f.view) : "") +
             (f.stage.empty() ? "" : " at " + f.stage) + ": " + f.code + ": " + f.message + "\n";
  }
  return out;
}

std::string EvaluationJson(const EvaluationReport& r) {
  std::string out = "{\"folder\":" + JsonString(r.folder) + ",\"model\":" + JsonString(r.model) +
                    ",\"method\":" + JsonString(r.method) + ",\"objects\":" + std::to_string(r.objects.size()) +
                    ",\"views\":" + std::to_string(r.objects.size() * r.views_per_object) + ",\"categories\":[";
  for (size_t c = 0; c < r.categories.size(); ++c) out += (c ? "," : "") + JsonString(r.categories[c]);
  out += "],\"stages\":[";
  for (size_t i = 0; i < r.stages.size(); ++i) {
    const std::string name = stage_name(r.stages[i]);
    const Tally t = accuracy(r.decisions, name, r.method_id);
    const auto confusion = confusion_percent(r.decisions, name, r.method_id, r.categories.size());
    out += std::string(i ? "," : "") + "{\"stage\":" + JsonString(name) + ",\"accuracy\":" + JsonNumber(t.percent()) +
           ",\"balanced_accuracy\":" +
           JsonNumber(balanced_accuracy(r.decisions, name, r.method_id, r.categories.size())) +
           ",\"correct\":" + std::to_string(t.correct) + ",\"total\":" + std::to_string(t.total) +
           ",\"calibration_error\":" + CalibrationErrorJson(StageProbabilityQuality(r, name)) + ",\"confusion\":{";
    bool first_row = true;
    for (size_t tr = 0; tr < r.categories.size(); ++tr) {
      if (std::find(r.object_truth.begin(), r.object_truth.end(), int(tr)) == r.object_truth.end()) continue;
      out += std::string(first_row ? "" : ",") + JsonString(r.categories[tr]) + ":{";
      first_row = false;
      for (size_t c = 0; c < r.model_categories; ++c)
        out += std::string(c ? "," : "") + JsonString(r.categories[c]) + ":" + JsonNumber(confusion[tr][c]);
      out += "}";
    }
    out += "}}";
  }
  out += "],\"misclassified\":[";
  bool first = true;
  for (const Stage& s : r.stages)
    for (const auto& [object, list] : Misclassified(r, stage_name(s)))
      for (const StageDecision* d : list) {
        out += std::string(first ? "" : ",") + "{\"object\":" + JsonString(r.objects[static_cast<size_t>(object)]) +
               ",\"view\":" + std::to_string(d->view) + ",\"stage\":" + JsonString(d->stage) +
               ",\"truth\":" + JsonString(r.categories[static_cast<size_t>(d->truth)]) + ",\"winner\":" +
               (d->winner >= 0 ? JsonString(r.categories[static_cast<size_t>(d->winner)]) : "null") + "}";
        first = false;
      }
  out += "],\"failures\":[";
  for (size_t i = 0; i < r.failures.size(); ++i) {
    const EvaluationReport::Failure& f = r.failures[i];
    out += std::string(i ? "," : "") + "{\"object\":" + JsonString(r.objects[static_cast<size_t>(f.object)]) +
           ",\"view\":" + std::to_string(f.view) + ",\"stage\":" + JsonString(f.stage) + ",\"code\":" +
           JsonString(f.code) + ",\"message\":" + JsonString(f.message) + "}";
  }
  return out + "],\"seconds\":" + JsonNumber(r.seconds) + "}";
}

}  // namespace glimpse::client
