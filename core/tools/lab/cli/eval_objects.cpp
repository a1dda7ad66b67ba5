// glimpse-lab eval's objects: the sources its flags name (dataset folders, the procedural zoo), their
// roles (cross-validated, training only, tested only, unknown), the objects drawn and held out, and the
// checks that would otherwise make the figures wrong.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "eval.h"

namespace glimpse::lab {

namespace {

// The objects of every folder in `dirs`, each given `role`.
Expected<std::vector<EvalObject>> load_sources(const std::vector<std::string>& dirs, EvalRole role, uint64_t seed,
                                               size_t max_objects, int threads) {
  std::vector<EvalObject> all;
  for (const std::string& dir : dirs) {
    Expected<std::vector<EvalObject>> loaded = std::vector<EvalObject>{};
    if (dir.rfind("zoo:", 0) == 0) {  // the procedural zoo as a source: zoo:N objects per category
      const long n = std::strtol(dir.c_str() + 4, nullptr, 10);
      if (n <= 0) return invalid_argument("'" + dir + "': want zoo:N with N objects per category");
      std::fprintf(stderr, "making the zoo: %ld objects per category ...\n", n);
      loaded = zoo_objects(static_cast<size_t>(n), seed);
    } else {
      std::fprintf(stderr, "loading %s ...\n", dir.c_str());
      loaded = load_dataset_objects(dir, seed, max_objects, threads);
    }
    if (!loaded.ok()) return loaded.error();
    for (EvalObject& o : *loaded) {
      o.role = role;
      all.push_back(std::move(o));
    }
  }
  return all;
}

// --hold-out: the named categories' objects become unknown (tested, never learnt; training-only ones
// are dropped). An open-set evaluation from known data alone: each category in turn plays "none of these".
Status hold_out(std::vector<EvalObject>& objects, const std::string& list) {
  std::set<std::string> present, held;
  for (const EvalObject& x : objects)
    if (x.role != EvalRole::kUnknown) present.insert(x.category);
  for (const std::string& c : split_list(list)) {
    if (!present.count(c)) {
      std::string names;
      for (const std::string& p : present) names += (names.empty() ? "" : ", ") + p;
      return invalid_argument("--hold-out: no object of category '" + c + "' (categories: " + names + ")");
    }
    held.insert(c);
  }
  std::erase_if(objects, [&](const EvalObject& x) { return x.role == EvalRole::kTrainOnly && held.count(x.category); });
  std::set<std::string> learnt;
  for (EvalObject& x : objects) {
    if (x.role == EvalRole::kUnknown) continue;
    if (held.count(x.category)) x.role = EvalRole::kUnknown;
    else if (x.role != EvalRole::kTestOnly) learnt.insert(x.category);
  }
  if (learnt.size() < 2) return invalid_argument("--hold-out: at least two learnt categories must remain");
  return {};
}

// --pick-objects N: N objects of each category of each source, drawn by the seed. The draw depends on
// the source, the category and the ids alone, so a folder given on both sides (--train X --test X) tests
// the very objects it learnt, as the paper's tables appear to (57 of their 60 figures are k/18: 3
// objects x 6 views per category).
void pick_objects(std::vector<EvalObject>& objects, size_t n, uint64_t seed) {
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> ids;  // (source, category) -> ids
  for (const EvalObject& x : objects) ids[{x.source, x.category}].push_back(x.id);
  std::set<std::tuple<std::string, std::string, std::string>> kept;
  for (auto& [key, list] : ids) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a of "source/category"
    for (unsigned char c : key.first + '/' + key.second) h = (h ^ c) * 0x100000001b3ull;
    std::mt19937_64 rng(seed ^ h);
    for (size_t i = list.size(); i > 1; --i) std::swap(list[i - 1], list[rng() % i]);  // Fisher-Yates
    for (size_t i = 0; i < std::min(n, list.size()); ++i) kept.insert({key.first, key.second, list[i]});
  }
  std::erase_if(objects, [&](const EvalObject& x) { return !kept.count({x.source, x.category, x.id}); });
}

// Across sources every tested category must be learnt: a category the model never saw cannot be right,
// and its objects belong in --unknown.
Status check_tested_categories_learnt(const std::vector<EvalObject>& objects) {
  std::set<std::string> learnt, missing;
  for (const EvalObject& x : objects)
    if (x.role == EvalRole::kTrainOnly) learnt.insert(x.category);
  for (const EvalObject& x : objects)
    if (x.role == EvalRole::kTestOnly && !learnt.count(x.category)) missing.insert(x.category);
  if (missing.empty()) return {};
  std::string names;
  for (const std::string& c : missing) names += (names.empty() ? "" : ", ") + c;
  return invalid_argument("--test: categories no training source holds: " + names +
                          " (objects of categories the model never learnt go in --unknown)");
}

// The objects of --data or --train (then --also-train, --unknown and --test beside them), or of the
// procedural zoo; `source` says where they come from. 0, or the exit code once the reason is printed.
int load_objects(const EvalOptions& o, const EvalParams& params, size_t max_objects, std::vector<EvalObject>& objects,
                 std::string& source) {
  if (o.data.empty() && o.train.empty()) {
    const size_t n = max_objects ? std::min(o.zoo, max_objects) : o.zoo;
    std::fprintf(stderr, "making the zoo: %zu objects per category ...\n", n);
    objects = zoo_objects(n, params.seed);
    source = "procedural zoo (make_zoo, seed " + std::to_string(params.seed) + ")";
    return 0;
  }
  const bool cross = !o.train.empty();
  auto first = load_sources(split_list(cross ? o.train : o.data), cross ? EvalRole::kTrainOnly : EvalRole::kCrossValidate,
                            params.seed, max_objects, params.threads);
  if (!first.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", first.error().message.c_str());
    return 1;
  }
  objects = std::move(*first);
  source = "meshes in " + (cross ? o.train : o.data);
  // Sources beside the evaluated ones (--also-train, --unknown): false after printing why they failed.
  auto add_sources = [&](const std::string& list, EvalRole role, const char* flag) {
    if (list.empty()) return true;
    auto extra = load_sources(split_list(list), role, params.seed, max_objects, params.threads);
    if (!extra.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: %s: %s\n", flag, extra.error().message.c_str());
      return false;
    }
    for (EvalObject& x : *extra) objects.push_back(std::move(x));
    return true;
  };
  if (!add_sources(o.also_train, EvalRole::kTrainOnly, "--also-train")) return 1;
  if (!o.also_train.empty()) source += " (also trained on " + o.also_train + ")";
  if (!add_sources(o.unknown, EvalRole::kUnknown, "--unknown")) return 1;
  if (!o.unknown.empty()) source += " (unknown: " + o.unknown + ")";
  if (!cross) return 0;
  auto second = load_sources(split_list(o.test), EvalRole::kTestOnly, params.seed, max_objects, params.threads);
  if (!second.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", second.error().message.c_str());
    return 1;
  }
  for (EvalObject& x : *second) objects.push_back(std::move(x));
  source = "trained on " + o.train + (o.also_train.empty() ? "" : "," + o.also_train) + ", tested on " + o.test +
           (o.unknown.empty() ? "" : " and on " + o.unknown + " (unknown)");
  if (Status s = check_tested_categories_learnt(objects); !s.ok()) {
    std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
    return 2;
  }
  return 0;
}

}  // namespace

// A source named twice (its objects learnt twice, or learnt and cross-validated at once) is an error;
// --train X --test X is not (resubstitution, which the report flags).
Status check_sources(const EvalOptions& o) {
  if (o.data.empty() && o.train.empty() && (!o.unknown.empty() || !o.also_train.empty()))
    return invalid_argument("--unknown and --also-train go with --data or --train (the zoo as a source: --data zoo:N)");
  std::map<std::string, std::string> seen;  // source -> the flag that named it
  auto key = [](const std::string& dir) {
    if (dir.rfind("zoo:", 0) == 0) return std::string("the zoo");  // zoo:3 and zoo:5 share their first objects
    std::error_code ec;
    const auto canonical = std::filesystem::weakly_canonical(dir, ec);
    return ec ? dir : canonical.string();
  };
  for (const auto& [list, flag] : {std::pair{o.data, "--data"}, {o.train, "--train"}, {o.also_train, "--also-train"},
                                   {o.unknown, "--unknown"}}) {
    for (const std::string& dir : split_list(list))
      if (auto [it, fresh] = seen.emplace(key(dir), flag); !fresh)
        return invalid_argument(std::string(flag) + ": " + dir + " is named already (" + it->second +
                                "): its objects would be learnt twice, or learnt and tested at once");
  }
  std::set<std::string> tests;
  for (const std::string& dir : split_list(o.test)) {
    if (!tests.insert(key(dir)).second) return invalid_argument("--test: " + dir + " is named twice");
    if (const auto it = seen.find(key(dir)); it != seen.end() && it->second != std::string("--train"))
      return invalid_argument("--test: " + dir + " is named already (" + it->second + ")");
  }
  return {};
}

int gather_objects(const EvalOptions& o, const EvalParams& params, std::vector<EvalObject>& objects,
                   std::string& source) {
  const size_t max_objects = o.quick && o.max_objects == 0 ? 8 : o.max_objects;
  if (int rc = load_objects(o, params, max_objects, objects, source); rc != 0) return rc;
  if (o.pick_objects > 0) {
    pick_objects(objects, o.pick_objects, params.seed);
    source += " (" + std::to_string(o.pick_objects) + " objects per category drawn by seed " + std::to_string(params.seed) + ")";
  }
  if (o.poses == "given")
    for (EvalObject& x : objects) x.any_pose = false;
  if (!o.hold_out.empty()) {
    if (Status s = hold_out(objects, o.hold_out); !s.ok()) {
      std::fprintf(stderr, "glimpse-lab eval: %s\n", s.error().message.c_str());
      return 2;
    }
    source += " (held out as unknown: " + o.hold_out + ")";
  }
  return 0;
}

}  // namespace glimpse::lab
