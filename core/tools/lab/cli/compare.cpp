// glimpse-lab compare: whether a change moved accuracy more than another draw of test objects could. It
// reads the decisions.csv of runs over the same views (before and after a change; several seeds' pairs
// pooled), pairs each view's two decisions and resamples objects, all of an object's paired views
// together.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "glimpse/lab/metrics.h"
#include "glimpse/expected.h"

namespace glimpse::lab {
namespace {

struct CompareOptions {
  std::vector<std::string> runs;  // BEFORE AFTER [BEFORE AFTER ...]
  double level = 0.95;
  size_t draws = 2000;
  uint64_t seed = 1;
};

// A known view's decision of one method at one stage: (object, view, stage, method) -> right.
using ViewKey = std::tuple<std::string, std::string, std::string, std::string>;
using RunDecisions = std::map<ViewKey, bool>;

// decisions.csv of a run (the file, or the report folder holding it). Views of objects of no learnt
// category (truth "unknown:...") are left out: accuracy is over known views, as the report's.
Expected<RunDecisions> read_run(const std::string& run) {
  std::filesystem::path path(run);
  if (std::filesystem::is_directory(path)) path /= "decisions.csv";
  std::ifstream in(path);
  if (!in) return not_found(path.string() + ": cannot read (a report folder or its decisions.csv)");
  std::string line;
  if (!std::getline(in, line)) return invalid_argument(path.string() + ": empty, no header");
  auto split = [](const std::string& text) {
    std::vector<std::string> fields;
    std::stringstream s(text);
    for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
    if (!text.empty() && text.back() == ',') fields.emplace_back();
    return fields;
  };
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line);
  std::vector<size_t> at;
  for (const char* name : {"object", "view", "stage", "method", "truth", "winner"}) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) return invalid_argument(path.string() + ": no column '" + name + "' in its header (a decisions.csv of glimpse-lab eval?)");
    at.push_back(static_cast<size_t>(it - header.begin()));
  }
  RunDecisions out;
  for (size_t number = 2; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // a file saved with CRLF line ends
    if (line.empty()) continue;
    const std::vector<std::string> f = split(line);
    if (f.size() != header.size())
      return invalid_argument(path.string() + ":" + std::to_string(number) + ": " + std::to_string(f.size()) +
                              " fields where the header has " + std::to_string(header.size()));
    const std::string& truth = f[at[4]];
    if (truth.rfind("unknown", 0) == 0) continue;
    const ViewKey key{f[at[0]], f[at[1]], f[at[2]], f[at[3]]};
    if (!out.emplace(key, f[at[5]] == truth).second)
      return invalid_argument(path.string() + ":" + std::to_string(number) + ": a second decision of object " +
                              f[at[0]] + " view " + f[at[1]] + " at " + f[at[2]] + " by " + f[at[3]]);
  }
  if (out.empty()) return invalid_argument(path.string() + ": no decision of a known view");
  return out;
}

// The seed a run's report.md records beside its decisions.csv, if it has one.
std::optional<std::string> run_seed(const std::string& run) {
  std::filesystem::path path(run);
  path = std::filesystem::is_directory(path) ? path / "report.md" : path.parent_path() / "report.md";
  std::ifstream in(path);
  const std::string row = "| seed (`--seed`) | ";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(row, 0) == 0) return line.substr(row.size(), line.find(' ', row.size()) - row.size());
  return std::nullopt;
}

// Views per object in a run: with another --views, view k is another camera.
std::map<std::string, size_t> views_per_object(const RunDecisions& run) {
  std::map<std::string, std::set<std::string>> views;
  for (const auto& [key, right] : run) views[std::get<0>(key)].insert(std::get<1>(key));
  std::map<std::string, size_t> out;
  for (const auto& [object, v] : views) out[object] = v.size();
  return out;
}

int run_compare(const CompareOptions& o) {
  if (o.runs.size() < 2 || o.runs.size() % 2)
    return std::fprintf(stderr, "compare takes runs in pairs, BEFORE AFTER [BEFORE AFTER ...]: %zu given\n", o.runs.size()), 2;
  // Per (method, stage): the paired views of every pair. An object is one unit across the pairs: under
  // another seed it is the same mesh, so its views there are not another draw of test objects.
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::string, int> units;
  std::map<std::pair<std::string, std::string>, std::vector<PairedView>> paired;
  size_t unpaired = 0;
  for (size_t p = 0; p < o.runs.size(); p += 2) {
    auto before = read_run(o.runs[p]);
    auto after = before.ok() ? read_run(o.runs[p + 1]) : before;
    for (const auto* r : {&before, &after})
      if (!r->ok()) return std::fprintf(stderr, "compare: %s\n", r->error().message.c_str()), 1;
    // A pair is one draw of views seen before and after a change: the same seed, the same views.
    if (const auto a = run_seed(o.runs[p]), b = run_seed(o.runs[p + 1]); a && b && *a != *b)
      return std::fprintf(stderr, "compare: %s and %s drew with seeds %s and %s: not the same views (nor, for the zoo, "
                                  "the same objects); pair runs of one seed\n", o.runs[p].c_str(), o.runs[p + 1].c_str(),
                          a->c_str(), b->c_str()), 1;
    {
      const auto a = views_per_object(*before), b = views_per_object(*after);
      for (const auto& [object, n] : a)
        if (const auto it = b.find(object); it != b.end() && it->second != n)
          return std::fprintf(stderr, "compare: %s has %zu views of %s and %s has %zu: with another --views a view's "
                                      "index is another camera\n", o.runs[p].c_str(), n, object.c_str(),
                              o.runs[p + 1].c_str(), it->second), 1;
    }
    size_t both = 0;
    for (const auto& [key, right] : *before) {
      const auto it = after->find(key);
      if (it == after->end()) continue;
      ++both;
      const auto& [object, view, stage, method] = key;
      const auto group = std::make_pair(method, stage);
      if (!paired.count(group)) order.push_back(group);
      const int unit = units.emplace(object, static_cast<int>(units.size())).first->second;
      paired[group].push_back({unit, right, it->second});
    }
    unpaired += before->size() + after->size() - 2 * both;
  }
  if (paired.empty()) return std::fprintf(stderr, "compare: no view is decided in both runs of any pair\n"), 1;
  std::sort(order.begin(), order.end());
  std::printf("%zu pair%s of runs; accuracy %% of known views, after - before in points; the interval holds "
              "%g %% of the differences of %zu resamples of the tested objects (seed %llu), all of an "
              "object's paired views drawn together\n\n",
              o.runs.size() / 2, o.runs.size() == 2 ? "" : "s", 100 * o.level, o.draws,
              static_cast<unsigned long long>(o.seed));
  std::printf("| method | stage | views | objects | before | after | difference | interval | turned right | turned wrong |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---|---:|---:|\n");
  for (const auto& group : order) {
    const PairedDifference d = paired_difference(paired[group], o.level, o.draws, o.seed);
    std::printf("| %s | %s | %zu | %zu | %.1f | %.1f | %+.1f | %+.1f to %+.1f | %zu | %zu |\n", group.first.c_str(),
                group.second.c_str(), d.views, d.units, d.before, d.after, d.difference, d.interval.low,
                d.interval.high, d.turned_right, d.turned_wrong);
  }
  if (unpaired) std::printf("\n%zu known views decided in only one run of their pair are left out\n", unpaired);
  return 0;
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "whether a change moved accuracy more than another draw of test objects could (paired runs' decisions.csv)");
  cmd->add_option("runs", o->runs,
                  "BEFORE AFTER [BEFORE AFTER ...]: eval report folders (or their decisions.csv) over the same views; "
                  "several pairs (e.g. seeds) are pooled, an object's views in every pair resampled as one")
      ->required();
  cmd->add_option("--level", o->level, "the interval's coverage")->capture_default_str()->check(CLI::Range(0.5, 0.999));
  cmd->add_option("--draws", o->draws, "resamples of the objects")->capture_default_str()->check(CLI::Range(100, 1000000));
  cmd->add_option("--seed", o->seed, "the resampling's seed")->capture_default_str();
  cmd->callback([o] {
    if (int rc = run_compare(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace glimpse::lab
