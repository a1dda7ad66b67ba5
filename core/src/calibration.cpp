// Calibration: what a model learns about its own decisions from held-out folds of its training set
// (inner cross-validation by object), so that no threshold is set on the clouds it will be judged on.
// Today: the score margin at which its decisions can be trusted, which makes a streamed decision settle.
#include <algorithm>
#include <map>
#include <random>

#include "model_impl.h"

namespace glimpse {

namespace {
uint32_t fnv1a(const std::string& s) {  // std::hash differs between standard libraries
  uint32_t h = 2166136261u;
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}
}  // namespace

std::vector<int> stratified_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed) {
  std::vector<int> fold(object_categories.size(), 0);
  if (folds < 1) return fold;
  std::map<std::string, std::vector<size_t>> by_category;
  for (size_t i = 0; i < object_categories.size(); ++i) by_category[object_categories[i]].push_back(i);
  int start = 0;  // rotate so small categories do not all start filling fold 0
  for (auto& [name, members] : by_category) {
    std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), fnv1a(name)};
    std::mt19937_64 rng(seq);
    // Fisher-Yates with our own index draw: std::shuffle's use of the engine is implementation-defined.
    for (size_t i = members.size(); i > 1; --i) std::swap(members[i - 1], members[rng() % i]);
    for (size_t j = 0; j < members.size(); ++j) fold[members[j]] = static_cast<int>((start + j) % folds);
    start = static_cast<int>((start + members.size()) % folds);
  }
  return fold;
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

Calibration calibrate(const ModelImpl& impl, MethodId method, const std::vector<Eigen::MatrixXd>& histograms,
                      const std::vector<int>& labels, const std::vector<int>& objects,
                      const std::vector<std::string>& object_categories, int categories, int threads) {
  const TrainParams& p = impl.params;
  Calibration c;
  c.method = method;
  const int folds = p.calibration_folds;
  if (folds < 2) return c;
  // Every category needs objects in at least two inner folds, or a fold learns nothing of it.
  std::map<std::string, size_t> per_category;
  for (const std::string& cat : object_categories) ++per_category[cat];
  for (const auto& [cat, n] : per_category)
    if (n < 2) return c;
  const std::vector<int> object_fold = stratified_folds(object_categories, folds, p.seed + 101);
  const std::vector<MethodId> parts = component_methods(impl, method);
  std::vector<std::pair<double, bool>> decisions;
  size_t correct = 0;
  for (int k = 0; k < folds; ++k) {
    std::vector<Eigen::Index> train_rows, test_rows;
    for (size_t i = 0; i < labels.size(); ++i)
      (object_fold[static_cast<size_t>(objects[i])] == k ? test_rows : train_rows).push_back(static_cast<Eigen::Index>(i));
    if (test_rows.empty()) continue;
    std::vector<int> train_labels, train_groups;
    for (Eigen::Index i : train_rows) train_labels.push_back(labels[static_cast<size_t>(i)]), train_groups.push_back(objects[static_cast<size_t>(i)]);
    std::vector<int> seen(static_cast<size_t>(categories), 0);
    for (int l : train_labels) seen[static_cast<size_t>(l)] = 1;
    if (std::count(seen.begin(), seen.end(), 0)) continue;  // a category wholly in this fold
    Eigen::VectorXd dummy;
    std::vector<Eigen::MatrixXd> scores(parts.size());
    bool ok = true;
    for (size_t j = 0; j < parts.size() && ok; ++j) {
      const Eigen::MatrixXd& h = histograms[static_cast<size_t>(parts[j])];
      Eigen::MatrixXd train_h(static_cast<Eigen::Index>(train_rows.size()), h.cols());
      for (size_t r = 0; r < train_rows.size(); ++r) train_h.row(static_cast<Eigen::Index>(r)) = h.row(train_rows[r]);
      DecisionParams dp = p.decision;
      if (parts[j] == MethodId::kBoG) dp.max_pca_dims = p.bog_pca_dims;
      auto stage = fit_decision(train_h, train_labels, categories, dp, p.seed + 10 + static_cast<uint64_t>(parts[j]),
                                threads, train_groups);
      if (!stage.ok()) {
        ok = false;
        break;
      }
      scores[j].resize(static_cast<Eigen::Index>(test_rows.size()), categories);
      for (size_t r = 0; r < test_rows.size(); ++r)
        scores[j].row(static_cast<Eigen::Index>(r)) = decide(*stage, h.row(test_rows[r]).transpose()).transpose();
    }
    if (!ok) continue;
    for (size_t r = 0; r < test_rows.size(); ++r) {
      Eigen::VectorXd s = Eigen::VectorXd::Zero(categories);
      for (const Eigen::MatrixXd& m : scores) s += m.row(static_cast<Eigen::Index>(r)).transpose();
      s /= double(std::max<size_t>(1, scores.size()));  // the fusion's mean, as method_scores
      const int winner = argmax(s);
      double second = 0;
      for (int i = 0; i < categories; ++i)
        if (i != winner) second = std::max(second, s[i]);
      const bool right = winner == labels[static_cast<size_t>(test_rows[r])];
      decisions.push_back({s[winner] - second, right});
      correct += right;
    }
  }
  c.held_out = decisions.size();
  if (decisions.empty()) return c;
  c.held_out_accuracy = double(correct) / double(decisions.size());
  c.settle_margin = settle_margin(std::move(decisions), p.settle_precision, 20);
  return c;
}

}  // namespace glimpse
