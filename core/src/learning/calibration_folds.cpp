// Folds of objects dealt by category (the evaluation's and calibration's), and the settle margin at
// which held-out decisions are right often enough.
#include <algorithm>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "glimpse/learning/calibration.h"
#include "glimpse/random.h"

namespace glimpse {

namespace {

// Per category (in name order) its objects shuffled (seeded) and dealt round robin from `first(name,
// the fold the category before it ended at)`.
std::vector<int> dealt_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed,
                             const std::function<int(const std::string&, int)>& first) {
  std::vector<int> fold(object_categories.size(), 0);
  if (folds < 1) return fold;
  std::map<std::string, std::vector<size_t>> by_category;
  for (size_t i = 0; i < object_categories.size(); ++i) by_category[object_categories[i]].push_back(i);
  int end = 0;
  for (auto& [name, members] : by_category) {
    std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), name_hash(name)};
    std::mt19937_64 rng(seq);
    // Fisher-Yates with our own index draw: std::shuffle's use of the engine is implementation-defined.
    for (size_t i = members.size(); i > 1; --i) std::swap(members[i - 1], members[rng() % i]);
    const int start = first(name, end);
    for (size_t j = 0; j < members.size(); ++j) fold[members[j]] = static_cast<int>((start + j) % folds);
    end = static_cast<int>((start + members.size()) % folds);
  }
  return fold;
}

}  // namespace

std::vector<int> stratified_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed) {
  // Rotated so small categories do not all start filling fold 0.
  return dealt_folds(object_categories, folds, seed, [](const std::string&, int end) { return end; });
}

std::vector<int> calibration_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed) {
  return dealt_folds(object_categories, folds, seed, [&](const std::string& name, int) {
    return static_cast<int>(splitmix64(seed, name_hash(name)) % static_cast<uint64_t>(folds));
  });
}

double settle_margin(std::vector<std::pair<double, bool>> decisions, double precision, size_t min_count) {
  if (decisions.size() < min_count) return 0;
  std::sort(decisions.begin(), decisions.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  // The lowest margin m such that the decisions at or above m are at least `precision` right (counted
  // once at least min_count of them are in): from the top down, the last place the share still holds.
  double best = 0;
  size_t right = 0;
  for (size_t i = 0; i < decisions.size(); ++i) {
    right += decisions[i].second;
    const bool tie_next = i + 1 < decisions.size() && decisions[i + 1].first == decisions[i].first;
    if (tie_next || i + 1 < min_count) continue;
    if (double(right) >= precision * double(i + 1)) best = decisions[i].first;
  }
  return best > 0 ? best : decisions.front().first + 1e-9;  // never right enough: settle on nothing seen
}

}  // namespace glimpse
