// Leave one source out (evaluation.h): each source tested by a model of every other one, per category,
// "closest" beside "right and accepted", with object-bootstrap intervals.
#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

#include "glimpse/lab/evaluation.h"

namespace glimpse {

namespace {

// The decisions of `method` at `stage` on known views of `category` (-1: every category), with a view
// called unknown counted as no decision: accuracy() of these is "right and accepted".
std::vector<StageDecision> known_views(const std::vector<StageDecision>& decisions, const std::string& stage,
                                       MethodId method, int category, bool accepted_only) {
  std::vector<StageDecision> out;
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.stage != stage || d.truth < 0 || (category >= 0 && d.truth != category)) continue;
    out.push_back(d);
    if (accepted_only && d.unknown) out.back().winner = -1;
  }
  return out;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

SourceRow source_row(const EvalResult& run, const std::string& stage, MethodId method, int category) {
  const std::vector<StageDecision> all = known_views(run.decisions, stage, method, category, false);
  const std::vector<StageDecision> accepted = known_views(run.decisions, stage, method, category, true);
  SourceRow row;
  row.left_out = joined(run.test_sources);
  row.stage = stage;
  if (category >= 0) row.category = run.categories[size_t(category)];
  std::set<int> objects;
  for (const StageDecision& d : all) objects.insert(d.object), row.rejected += d.unknown;
  row.views = all.size();
  row.objects = objects.size();
  row.closest = accuracy(all, stage, method);
  row.accepted_right = accuracy(accepted, stage, method);
  row.closest_interval = accuracy_interval(all, stage, method);
  row.accepted_interval = accuracy_interval(accepted, stage, method);
  return row;
}

std::string cell(const Tally& t, const AccuracyInterval& ci) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f [%.1f, %.1f]", t.percent(), ci.low, ci.high);
  return buf;
}

std::string share(size_t part, size_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", whole ? 100.0 * double(part) / double(whole) : 0.0);
  return buf;
}

// One run's rows: every category together, then each, at every stage.
std::vector<SourceRow> run_rows(const EvalResult& run, MethodId method) {
  std::vector<SourceRow> rows;
  for (int c = -1; c < int(run.categories.size()); ++c)
    for (const Stage& stage : run.params.stages)
      if (SourceRow row = source_row(run, stage_name(stage), method, c); row.views > 0) rows.push_back(std::move(row));
  return rows;
}

}  // namespace

std::vector<SourceRow> leave_one_source_out_rows(const std::vector<EvalResult>& runs, MethodId method) {
  std::vector<SourceRow> rows;
  for (const EvalResult& run : runs)
    for (SourceRow& row : run_rows(run, method)) rows.push_back(std::move(row));
  return rows;
}

std::string leave_one_source_out_report(const std::vector<EvalResult>& runs, MethodId method) {
  std::vector<std::vector<SourceRow>> rows;  // per run
  for (const EvalResult& run : runs) rows.push_back(run_rows(run, method));
  std::ostringstream o;
  o << "# Leave one source out (" << method_name(method) << ")\n\n"
    << "Each source is tested by a model of every other one (their objects, plus what every run learns "
       "besides); nothing of the tested source is learnt. **Closest**: the winner is right, \"unknown\" "
       "ignored; **right and accepted**: right and not called unknown at the model's default operating point. "
       "In brackets: the interval holding 95 % of 2000 resamples of the tested objects. Each run's own report "
       "is in the folder named after the source.\n\n";
  o << "| source left out | trained on | stage | objects | views | closest | right and accepted | known called unknown % |\n"
    << "|---|---|---|---:|---:|---|---|---:|\n";
  for (size_t i = 0; i < runs.size(); ++i)
    for (const SourceRow& r : rows[i])
      if (r.category.empty())
        o << "| " << r.left_out << " | " << joined(runs[i].train_sources) << " | " << r.stage << " | " << r.objects
          << " | " << r.views << " | " << cell(r.closest, r.closest_interval) << " | "
          << cell(r.accepted_right, r.accepted_interval) << " | " << share(r.rejected, r.views) << " |\n";
  if (std::any_of(runs.begin(), runs.end(), [](const EvalResult& r) { return !r.unknown_categories.empty(); })) {
    o << "\n## Open set across sources\n\nThe objects of no learnt category tested beside each source (each run's "
         "report has them per class). AUROC: an unknown view more novel than a known one; accepted: at the "
         "model's default operating point.\n\n"
      << "| source left out | stage | AUROC | known accepted % | unknown accepted % | known / unknown views |\n"
      << "|---|---|---:|---:|---:|---:|\n";
    for (const EvalResult& run : runs) {
      if (run.unknown_categories.empty()) continue;
      for (const OpenSetRow& row : open_set_summary(run.decisions, run.params.stages, method, run.unknown_categories.size())) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "| %s | %s | %.3f | %.1f | %.1f | %zu / %zu |\n", joined(run.test_sources).c_str(),
                      row.stage.c_str(), row.auroc, row.known_acceptance, row.false_acceptance, row.known, row.unknown);
        o << buf;
      }
    }
  }
  o << "\n## Per category\n\n| source left out | category | stage | objects | closest | right and accepted | known called unknown % |\n"
    << "|---|---|---|---:|---|---|---:|\n";
  for (const std::vector<SourceRow>& run_rows : rows)
    for (const SourceRow& r : run_rows)
      if (!r.category.empty())
        o << "| " << r.left_out << " | " << r.category << " | " << r.stage << " | " << r.objects << " | "
          << cell(r.closest, r.closest_interval) << " | " << cell(r.accepted_right, r.accepted_interval) << " | "
          << share(r.rejected, r.views) << " |\n";
  return o.str();
}

}  // namespace glimpse
