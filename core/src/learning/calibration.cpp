// Calibration: what a model learns about its own decisions from held-out folds of its training set
// (inner cross-validation by object), so that no threshold is set on the clouds it will be judged on.
// The score margin at which its decisions can be trusted (a streamed decision settles there), and how
// far from anything learnt its known clouds fall, so that a cloud of no learnt category can be told
// ("none of these") with no example of one.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "glimpse/learning/calibration.h"

#include "glimpse/learning/novelty.h"
#include "glimpse/learning/scores.h"

namespace glimpse {

namespace {
uint32_t fnv1a(const std::string& s) {  // std::hash differs between standard libraries
  uint32_t h = 2166136261u;
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}

double median(std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// What the held-out decisions of the inner folds measured: per decision, its winner and, per component
// method, every category's nearest reference.
struct HeldOut {
  std::vector<int> winners;
  std::vector<Eigen::VectorXd> scores;                  // [decision]: the components' mean scores (novelty divides by them)
  std::vector<std::vector<NearestReferences>> nearest;  // [decision][component]
  // The same of each decision's top-down prefix (TrainParams::novelty_prefix); empty: it has none.
  std::vector<Eigen::VectorXd> prefix_scores;
  std::vector<std::vector<NearestReferences>> prefix_nearest;
};

// Novelty scales: per component, category and kind of nearest reference (a top-down prefix or a whole
// cloud: a full table is far from every other full table, its top close to every other top), the
// median distance from the held-out decisions decided as that category (right or wrong: an unknown
// cloud is decided as something too) to its nearest reference; and the median of what the stage's PCA
// leaves out of the held-out histograms, per kind of the winner's nearest reference (last two). Then the
// held-out novelties' quantiles.
void calibrate_novelty(Calibration& c, const HeldOut& h, size_t components, int categories, double known_acceptance) {
  if (h.winners.empty() || components == 0) return;
  const size_t n_cat = static_cast<size_t>(categories);
  c.novelty_scale.assign(components, std::vector<double>(2 * n_cat + 2, 1.0));
  for (size_t j = 0; j < components; ++j) {
    std::vector<double> all, residuals[2];
    for (size_t i = 0; i < h.winners.size(); ++i) {
      const NearestReferences& n = h.nearest[i][j];
      residuals[n.whole[static_cast<size_t>(h.winners[i])]].push_back(n.residual);
    }
    for (size_t kind = 0; kind < 2; ++kind) {
      const double m = median(residuals[kind].size() >= 5 ? residuals[kind] : residuals[1 - kind]);
      c.novelty_scale[j][2 * n_cat + kind] = m > 0 ? m : 1.0;
    }
    std::vector<std::vector<double>> of(n_cat), of_kind(2 * n_cat);
    for (size_t i = 0; i < h.winners.size(); ++i) {
      const size_t w = static_cast<size_t>(h.winners[i]);
      const NearestReferences& n = h.nearest[i][j];
      all.push_back(n.distance[h.winners[i]]);
      of[w].push_back(n.distance[h.winners[i]]);
      of_kind[2 * w + n.whole[w]].push_back(n.distance[h.winners[i]]);
    }
    const double component = median(all);
    for (size_t k = 0; k < 2 * n_cat; ++k) {
      // Too few to say: the category's, then the component's.
      const double m = of_kind[k].size() >= 5 ? median(of_kind[k]) : of[k / 2].size() >= 5 ? median(of[k / 2]) : component;
      c.novelty_scale[j][k] = m > 0 ? m : (component > 0 ? component : 1.0);
    }
  }
  std::vector<double> known;
  for (size_t i = 0; i < h.winners.size(); ++i) {
    Eigen::VectorXd n = category_novelty(c, h.nearest[i], h.scores[i]);
    if (!h.prefix_nearest[i].empty()) n = joint_novelty(n, category_novelty(c, h.prefix_nearest[i], h.prefix_scores[i]));
    if (n.size() && std::isfinite(n[h.winners[i]])) known.push_back(n[h.winners[i]]);
  }
  if (known.empty()) return;
  std::sort(known.begin(), known.end());
  c.novelty_quantiles.resize(kNoveltyQuantiles);
  for (size_t q = 0; q < kNoveltyQuantiles; ++q) {
    // The smallest novelty accepting at least this share of the held-out decisions.
    const double a = double(q) / double(kNoveltyQuantiles - 1);
    const size_t rank = static_cast<size_t>(std::ceil(a * double(known.size()) - 1e-9));
    c.novelty_quantiles[q] = known[std::min(known.size() - 1, rank > 0 ? rank - 1 : 0)];
  }
  c.known_acceptance = known_acceptance;
  c.novelty_threshold = novelty_threshold(c, known_acceptance);
}

// Per reference of a stage fitted on `rows`: whether it is a whole cloud. Rules whose references are
// centres, not training vectors, count every reference as whole.
std::vector<uint8_t> whole_references(DecisionRule rule, const std::vector<uint8_t>& whole, const std::vector<Eigen::Index>& rows) {
  if (rule != DecisionRule::kNearestReference && rule != DecisionRule::kNearestNeighbours) return {};
  std::vector<uint8_t> out;
  for (Eigen::Index r : rows) out.push_back(whole.empty() ? 1 : whole[static_cast<size_t>(r)]);
  return out;
}

// Per reference of a stage fitted on `rows`: its training object, numbered 0, 1, ... in the order met
// (empty for rules whose references are centres).
std::vector<uint32_t> object_references(DecisionRule rule, const std::vector<int>& objects, const std::vector<Eigen::Index>& rows) {
  if (rule != DecisionRule::kNearestReference && rule != DecisionRule::kNearestNeighbours) return {};
  std::map<int, uint32_t> number;
  std::vector<uint32_t> out;
  for (Eigen::Index r : rows) {
    const auto [it, fresh] = number.try_emplace(objects[static_cast<size_t>(r)], static_cast<uint32_t>(number.size()));
    out.push_back(it->second);
  }
  return out;
}

// Per category, how many of its nearest training objects a distance is taken over: `wanted`, or fewer
// where an inner training fold holds fewer objects of it, so held-out distances mean what the model's will.
std::vector<int> objects_per_category(const std::vector<int>& labels, const std::vector<int>& objects,
                                      const std::vector<int>& object_fold, int folds, int categories, int wanted) {
  std::map<int, int> category_of;
  for (size_t i = 0; i < labels.size(); ++i) category_of[objects[i]] = labels[i];
  std::vector<int> total(static_cast<size_t>(categories), 0), out(static_cast<size_t>(categories), wanted);
  std::vector<std::vector<int>> in_fold(static_cast<size_t>(folds), total);
  for (const auto& [o, c] : category_of) {
    ++total[static_cast<size_t>(c)];
    ++in_fold[static_cast<size_t>(object_fold[static_cast<size_t>(o)])][static_cast<size_t>(c)];
  }
  for (const std::vector<int>& held_out : in_fold)
    for (size_t c = 0; c < out.size(); ++c)
      if (const int learnt = total[c] - held_out[c]; learnt > 0) out[c] = std::min(out[c], learnt);
  return out;
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

Calibration calibrate(const ModelImpl& impl, MethodId method, const CalibrationRows& rows, bool measure_novelty,
                      int threads, const CancelFn& cancel) {
  const std::vector<Eigen::MatrixXd>& histograms = rows.histograms;
  const std::vector<Eigen::MatrixXd>& queries = rows.queries();
  const std::vector<Eigen::MatrixXd>& prefix_queries = rows.prefix_histograms;
  const std::vector<uint8_t>& has_prefix = rows.has_prefix;
  const std::vector<int>& labels = rows.labels;
  const std::vector<int>& objects = rows.objects;
  const std::vector<uint8_t>& whole = rows.whole;
  const std::vector<std::string>& object_categories = rows.object_categories;
  const int categories = rows.categories;
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
  const std::vector<int> novelty_objects =
      objects_per_category(labels, objects, object_fold, folds, categories, std::max(1, p.novelty_objects));
  std::vector<std::pair<double, bool>> decisions;
  HeldOut held_out;
  // Per held-out decision: the mean of the components' scores, the head's probabilities, the truth.
  std::vector<Eigen::VectorXd> means, head_probabilities;
  std::vector<int> truths;
  const bool with_head = method == MethodId::kFusion && impl.fusion_head.has_value() && !p.fusion_head_shares.empty();
  size_t correct = 0;
  for (int k = 0; k < folds; ++k) {
    if (cancel && cancel()) return c;  // the caller sees the cancel and stores nothing
    std::vector<Eigen::Index> train_rows, test_rows;
    for (size_t i = 0; i < labels.size(); ++i)
      (object_fold[static_cast<size_t>(objects[i])] == k ? test_rows : train_rows).push_back(static_cast<Eigen::Index>(i));
    if (test_rows.empty()) continue;
    std::vector<int> train_labels, train_groups;
    for (Eigen::Index i : train_rows) train_labels.push_back(labels[static_cast<size_t>(i)]), train_groups.push_back(objects[static_cast<size_t>(i)]);
    std::vector<int> seen(static_cast<size_t>(categories), 0);
    for (int l : train_labels) seen[static_cast<size_t>(l)] = 1;
    if (std::count(seen.begin(), seen.end(), 0)) continue;  // a category wholly in this fold
    std::vector<Eigen::MatrixXd> scores(parts.size());
    std::vector<std::vector<NearestReferences>> nearest(test_rows.size());
    // The held-out rows with a prefix (places in test_rows), and per one its components' mean score.
    std::vector<size_t> with_prefix;
    for (size_t r = 0; r < test_rows.size() && measure_novelty; ++r)
      if (static_cast<size_t>(test_rows[r]) < has_prefix.size() && has_prefix[static_cast<size_t>(test_rows[r])]) with_prefix.push_back(r);
    std::vector<Eigen::Index> prefix_rows;
    for (size_t r : with_prefix) prefix_rows.push_back(test_rows[r]);
    std::vector<Eigen::VectorXd> prefix_means(test_rows.size());
    std::vector<std::vector<NearestReferences>> prefix_nearest(test_rows.size());
    bool ok = true;
    for (size_t j = 0; j < parts.size() && ok; ++j) {
      const Eigen::MatrixXd& h = histograms[static_cast<size_t>(parts[j])];
      const Eigen::MatrixXd& q = queries[static_cast<size_t>(parts[j])];
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
      const std::vector<uint8_t> reference_whole = whole_references(stage->kind, whole, train_rows);
      const std::vector<uint32_t> reference_object = object_references(stage->kind, objects, train_rows);
      scores[j].resize(static_cast<Eigen::Index>(test_rows.size()), categories);
      std::vector<NearestReferences> component(test_rows.size());
      decide_rows_with_distances(*stage, q, test_rows, threads, [&](size_t r, StageScores&& answer) {
        scores[j].row(static_cast<Eigen::Index>(r)) = answer.scores.transpose();
        if (measure_novelty)
          component[r] = nearest_references(*stage, std::move(answer), reference_whole, reference_object, novelty_objects);
      });
      for (size_t r = 0; r < test_rows.size(); ++r) nearest[r].push_back(std::move(component[r]));
      if (prefix_rows.empty()) continue;
      decide_rows_with_distances(*stage, prefix_queries[static_cast<size_t>(parts[j])], prefix_rows, threads,
                                 [&](size_t k, StageScores&& answer) {
                                   Eigen::VectorXd& mean = prefix_means[with_prefix[k]];
                                   mean = mean.size() ? Eigen::VectorXd(mean + answer.scores) : answer.scores;
                                   prefix_nearest[with_prefix[k]].push_back(nearest_references(
                                       *stage, std::move(answer), reference_whole, reference_object, novelty_objects));
                                 });
    }
    if (!ok) continue;
    // The fusion's logistic decision, learnt on this fold's training rows like the stages.
    Eigen::MatrixXd probabilities;
    if (with_head && !(cancel && cancel())) {
      // Started from the model's own head (all the rows): LIBLINEAR stops at the same tolerance of the
      // same problem, in fewer steps.
      auto head = fit_chi2_logistic(fusion_head_rows(impl, histograms, train_rows, threads), train_labels, categories, p.fusion_head, threads,
                                    &*impl.fusion_head);
      if (head.ok()) {
        const Eigen::MatrixXd x = fusion_head_rows(impl, queries, test_rows, threads);
        probabilities.resize(x.rows(), categories);
        for (Eigen::Index r = 0; r < x.rows(); ++r)
          probabilities.row(r) = chi2_logistic_probabilities(*head, x.row(r).transpose()).transpose();
      }
    }
    for (size_t r = 0; r < test_rows.size(); ++r) {
      Eigen::VectorXd s = Eigen::VectorXd::Zero(categories);
      for (const Eigen::MatrixXd& m : scores) s += m.row(static_cast<Eigen::Index>(r)).transpose();
      s /= double(std::max<size_t>(1, scores.size()));  // the fusion's mean, as method_scores
      means.push_back(s);
      head_probabilities.push_back(probabilities.rows() ? Eigen::VectorXd(probabilities.row(static_cast<Eigen::Index>(r)).transpose())
                                                        : Eigen::VectorXd());
      truths.push_back(labels[static_cast<size_t>(test_rows[r])]);
      held_out.nearest.push_back(std::move(nearest[r]));
      held_out.prefix_scores.push_back(prefix_means[r] / double(std::max<size_t>(1, parts.size())));
      held_out.prefix_nearest.push_back(std::move(prefix_nearest[r]));
    }
  }
  if (means.empty()) return c;
  // The head's share: the one of fusion_head_shares whose held-out decisions are most often right, the
  // smallest on a tie. (Measured and dropped in stop 33: one share where the winner's nearest references
  // are whole training views and one where one is a prefix; full views are nearest to large prefixes.)
  if (with_head) {
    size_t best_right = 0;
    for (double share : p.fusion_head_shares) {
      if (!(share >= 0 && share <= 1)) continue;
      size_t right = 0;
      for (size_t i = 0; i < means.size(); ++i) right += argmax(fused_scores(means[i], head_probabilities[i], share)) == truths[i];
      if (right > best_right || (right == best_right && share < c.fusion_head_share)) best_right = right, c.fusion_head_share = share;
    }
  }
  for (size_t i = 0; i < means.size(); ++i) {
    const Eigen::VectorXd s = fused_scores(means[i], head_probabilities[i], c.fusion_head_share);
    const int winner = argmax(s);
    double second = 0;
    for (int k = 0; k < categories; ++k)
      if (k != winner) second = std::max(second, s[k]);
    const bool right = winner == truths[i];
    decisions.push_back({s[winner] - second, right});
    correct += right;
    held_out.winners.push_back(winner);
    held_out.scores.push_back(means[i]);  // novelty is over the nearest references' scores (method_decision)
  }
  c.held_out = decisions.size();
  c.held_out_accuracy = double(correct) / double(decisions.size());
  c.settle_margin = settle_margin(std::move(decisions), p.settle_precision, 20);
  if (measure_novelty) calibrate_novelty(c, held_out, parts.size(), categories, p.known_acceptance);
  if (!c.novelty_scale.empty()) {
    c.novelty_objects = novelty_objects;
    for (MethodId m : parts) {  // the model's own stages learnt every row
      std::vector<Eigen::Index> rows(labels.size());
      for (size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<Eigen::Index>(i);
      const DecisionRule kind = impl.stages[static_cast<int>(m)]->kind;
      c.reference_whole.push_back(whole_references(kind, whole, rows));
      c.reference_object.push_back(object_references(kind, objects, rows));
    }
  }
  return c;
}

}  // namespace glimpse
