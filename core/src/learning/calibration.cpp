// Calibration from held-out folds of the training set (inner cross-validation by object): the settle
// margin, the head's share, the probabilities' temperature (probabilities.cpp) and novelty's scales.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "glimpse/learning/calibration.h"

#include "glimpse/learning/novelty.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/learning/scores.h"
#include "glimpse/random.h"

namespace glimpse {

namespace {

double median(std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// What the held-out decisions of the inner folds measured: per decision, its truth, the components'
// mean scores, the fusion's logistic decision's probabilities, its winner (at the head's chosen share)
// and, per component method, every category's nearest reference.
struct HeldOut {
  std::vector<int> truths;
  std::vector<Eigen::VectorXd> scores;              // [decision]: the components' mean scores (novelty divides by them)
  std::vector<Eigen::VectorXd> head_probabilities;  // [decision]: empty without the head
  std::vector<int> winners;
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

// Per row, whether calibration decides it: about `queries` of the rows, each kept when a seeded hash of
// its key falls under queries / rows; empty (every row) when queries <= 0 or >= the rows.
std::vector<uint8_t> decided_rows(const std::vector<uint64_t>& keys, int queries, uint64_t seed) {
  const size_t n = keys.size();
  if (queries <= 0 || static_cast<size_t>(queries) >= n) return {};
  const double keep = double(queries) / double(n);
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = uniform01(splitmix64(seed, keys[i])) < keep;
  return out;
}

// Every category needs objects in at least two inner folds, or a fold learns nothing of it.
bool two_objects_per_category(const std::vector<std::string>& object_categories) {
  std::map<std::string, size_t> per_category;
  for (const std::string& cat : object_categories) ++per_category[cat];
  for (const auto& [cat, n] : per_category)
    if (n < 2) return false;
  return true;
}

// What every inner fold of one calibration shares.
struct InnerFolds {
  const ModelImpl& impl;
  const CalibrationRows& rows;
  std::vector<int> object_fold{};    // per object: its inner fold
  std::vector<MethodId> parts{};     // the calibrated method's components
  std::vector<int> novelty_objects{};  // per category (objects_per_category)
  std::vector<uint8_t> decided{};    // per row: whether it is decided held out (empty: every row)
  bool with_head = false;            // the fusion's logistic decision takes a share of its scores
  const std::vector<Chi2Logistic>* head_starts = nullptr;  // per fold: where its head's solver starts
  bool measure_novelty = false;
  int threads = 1;
};

// One inner fold: the other folds' rows learn, this fold's are decided. with_prefix: the places in
// test_rows of the rows whose prefix is decided too (only when novelty is measured); prefix_rows: those
// rows.
struct FoldRows {
  std::vector<Eigen::Index> train_rows, test_rows;
  std::vector<int> train_labels, train_groups;
  std::vector<size_t> with_prefix;
  std::vector<Eigen::Index> prefix_rows;
};

// Fold k's rows; none when it holds no row or a category lies wholly in it.
std::optional<FoldRows> fold_rows(const InnerFolds& in, int k) {
  const CalibrationRows& rows = in.rows;
  FoldRows f;
  for (size_t i = 0; i < rows.labels.size(); ++i) {
    if (in.object_fold[static_cast<size_t>(rows.objects[i])] != k) f.train_rows.push_back(static_cast<Eigen::Index>(i));
    else if (in.decided.empty() || in.decided[i]) f.test_rows.push_back(static_cast<Eigen::Index>(i));
  }
  if (f.test_rows.empty()) return std::nullopt;
  for (Eigen::Index i : f.train_rows)
    f.train_labels.push_back(rows.labels[static_cast<size_t>(i)]), f.train_groups.push_back(rows.objects[static_cast<size_t>(i)]);
  std::vector<int> seen(static_cast<size_t>(rows.categories), 0);
  for (int l : f.train_labels) seen[static_cast<size_t>(l)] = 1;
  if (std::count(seen.begin(), seen.end(), 0)) return std::nullopt;
  for (size_t r = 0; r < f.test_rows.size() && in.measure_novelty; ++r)
    if (static_cast<size_t>(f.test_rows[r]) < rows.has_prefix.size() && rows.has_prefix[static_cast<size_t>(f.test_rows[r])])
      f.with_prefix.push_back(r);
  for (size_t r : f.with_prefix) f.prefix_rows.push_back(f.test_rows[r]);
  return f;
}

// One fold's held-out decisions by the components' stages.
struct FoldDecisions {
  std::vector<Eigen::MatrixXd> scores;                         // [component]: held-out rows x categories
  std::vector<std::vector<NearestReferences>> nearest;         // [row][component]
  std::vector<Eigen::VectorXd> prefix_sums;                    // [row]: its prefix's scores, summed over components
  std::vector<std::vector<NearestReferences>> prefix_nearest;  // [row][component]
};

// The decision parameters of a held-out stage of method m: BoG's dimensions capped as in the model's
// stage, but with PCA only where the other methods have it (the model's BoG stage always has one).
DecisionParams held_out_stage_params(const TrainParams& p, MethodId m) {
  DecisionParams dp = p.decision;
  if (m == MethodId::kBoG) dp.max_pca_dims = p.bog_pca_dims;
  return dp;
}

// Component j's stage, fitted on the fold's training rows, decides its held-out rows (and for novelty
// their nearest references, and their prefixes). False when the stage cannot be fitted.
bool component_decisions(const InnerFolds& in, size_t j, const FoldRows& fold, FoldDecisions& out) {
  const CalibrationRows& rows = in.rows;
  const TrainParams& p = in.impl.params;
  const MethodId part = in.parts[j];
  const Eigen::MatrixXd& h = rows.histograms[static_cast<size_t>(part)];
  const Eigen::MatrixXd& q = rows.queries()[static_cast<size_t>(part)];
  Eigen::MatrixXd train_h(static_cast<Eigen::Index>(fold.train_rows.size()), h.cols());
  for (size_t r = 0; r < fold.train_rows.size(); ++r) train_h.row(static_cast<Eigen::Index>(r)) = h.row(fold.train_rows[r]);
  auto stage = fit_decision(train_h, fold.train_labels, rows.categories, held_out_stage_params(p, part),
                            p.seed + 10 + static_cast<uint64_t>(part), in.threads, fold.train_groups);
  if (!stage.ok()) return false;
  const std::vector<uint8_t> reference_whole = whole_references(stage->kind, rows.whole, fold.train_rows);
  const std::vector<uint32_t> reference_object = object_references(stage->kind, rows.objects, fold.train_rows);
  out.scores[j].resize(static_cast<Eigen::Index>(fold.test_rows.size()), rows.categories);
  std::vector<NearestReferences> component(fold.test_rows.size());
  decide_rows_with_distances(*stage, q, fold.test_rows, in.threads, [&](size_t r, StageScores&& answer) {
    out.scores[j].row(static_cast<Eigen::Index>(r)) = answer.scores.transpose();
    if (in.measure_novelty)
      component[r] = nearest_references(*stage, std::move(answer), reference_whole, reference_object, in.novelty_objects);
  });
  for (size_t r = 0; r < fold.test_rows.size(); ++r) out.nearest[r].push_back(std::move(component[r]));
  if (fold.prefix_rows.empty()) return true;
  decide_rows_with_distances(*stage, rows.prefix_histograms[static_cast<size_t>(part)], fold.prefix_rows, in.threads,
                             [&](size_t k, StageScores&& answer) {
                               Eigen::VectorXd& sum = out.prefix_sums[fold.with_prefix[k]];
                               sum = sum.size() ? Eigen::VectorXd(sum + answer.scores) : answer.scores;
                               out.prefix_nearest[fold.with_prefix[k]].push_back(nearest_references(
                                   *stage, std::move(answer), reference_whole, reference_object, in.novelty_objects));
                             });
  return true;
}

// The fusion's logistic decision learnt on the fold's training rows like the stages, started from fold k's
// start (a base model's head of the same fold) or the model's own head (all the rows it learns): LIBLINEAR
// stops at the same tolerance of the same problem, in fewer steps. Per held-out row its probabilities
// (empty when the fit fails); the head into `learnt`.
Eigen::MatrixXd held_out_head_probabilities(const InnerFolds& in, const FoldRows& fold, int k,
                                            std::optional<Chi2Logistic>& learnt_head) {
  const TrainParams& p = in.impl.params;
  Eigen::MatrixXd probabilities;
  std::vector<Eigen::Index> learnt;
  std::vector<int> labels;
  for (size_t i = 0; i < fold.train_rows.size(); ++i)
    if (in.rows.head_learns.empty() || in.rows.head_learns[static_cast<size_t>(fold.train_rows[i])])
      learnt.push_back(fold.train_rows[i]), labels.push_back(fold.train_labels[i]);
  const bool own_start = in.head_starts && static_cast<size_t>(k) < in.head_starts->size() &&
                         (*in.head_starts)[static_cast<size_t>(k)].weights.size() > 0;
  const Chi2Logistic* start = own_start ? &(*in.head_starts)[static_cast<size_t>(k)] : &*in.impl.fusion_head;
  auto head = fit_chi2_logistic(fusion_head_rows(in.impl, in.rows.histograms, learnt, in.threads), labels,
                                in.rows.categories, p.fusion_head, in.threads, start);
  if (head.ok()) {
    const Eigen::MatrixXd x = fusion_head_rows(in.impl, in.rows.queries(), fold.test_rows, in.threads);
    probabilities.resize(x.rows(), in.rows.categories);
    for (Eigen::Index r = 0; r < x.rows(); ++r)
      probabilities.row(r) = chi2_logistic_probabilities(*head, x.row(r).transpose()).transpose();
    learnt_head = std::move(*head);
  }
  return probabilities;
}

// Inner fold k's held-out decisions, added to `out` (its winners are chosen later, at the head's share),
// and its head; nothing when the fold has none or a component's stage cannot be fitted.
void decide_held_out_fold(const InnerFolds& in, int k, const CancelFn& cancel, HeldOut& out,
                          std::optional<Chi2Logistic>& head) {
  const std::optional<FoldRows> fold = fold_rows(in, k);
  if (!fold) return;
  const size_t n = fold->test_rows.size();
  FoldDecisions d{std::vector<Eigen::MatrixXd>(in.parts.size()), std::vector<std::vector<NearestReferences>>(n),
                  std::vector<Eigen::VectorXd>(n), std::vector<std::vector<NearestReferences>>(n)};
  for (size_t j = 0; j < in.parts.size(); ++j)
    if (!component_decisions(in, j, *fold, d)) return;
  Eigen::MatrixXd probabilities;
  if (in.with_head && !(cancel && cancel())) probabilities = held_out_head_probabilities(in, *fold, k, head);
  for (size_t r = 0; r < n; ++r) {
    Eigen::VectorXd s = Eigen::VectorXd::Zero(in.rows.categories);
    for (const Eigen::MatrixXd& m : d.scores) s += m.row(static_cast<Eigen::Index>(r)).transpose();
    s /= double(std::max<size_t>(1, d.scores.size()));  // the fusion's mean, as method_scores
    out.scores.push_back(s);  // novelty is over the nearest references' scores (method_decision)
    out.head_probabilities.push_back(probabilities.rows() ? Eigen::VectorXd(probabilities.row(static_cast<Eigen::Index>(r)).transpose())
                                                          : Eigen::VectorXd());
    out.truths.push_back(in.rows.labels[static_cast<size_t>(fold->test_rows[r])]);
    out.nearest.push_back(std::move(d.nearest[r]));
    out.prefix_scores.push_back(d.prefix_sums[r] / double(std::max<size_t>(1, in.parts.size())));
    out.prefix_nearest.push_back(std::move(d.prefix_nearest[r]));
  }
}

// The head's share: the one of `shares` whose held-out decisions are most often right, the smallest on a
// tie; `share` when none is right.
double choose_head_share(const std::vector<double>& shares, const HeldOut& h, double share) {
  size_t best_right = 0;
  for (double candidate : shares) {
    if (!(candidate >= 0 && candidate <= 1)) continue;
    size_t right = 0;
    for (size_t i = 0; i < h.scores.size(); ++i)
      right += argmax(fused_scores(h.scores[i], h.head_probabilities[i], candidate)) == h.truths[i];
    if (right > best_right || (right == best_right && candidate < share)) best_right = right, share = candidate;
  }
  return share;
}

// The held-out decisions at the head's share: their winners, the share right, the settle margin (the
// lowest margin at which `precision` of them are right) and the temperature of their probabilities.
void settle_on_held_out(Calibration& c, HeldOut& h, int categories, double precision) {
  std::vector<std::pair<double, bool>> decisions;
  std::vector<Eigen::VectorXd> fused;
  size_t correct = 0;
  for (size_t i = 0; i < h.scores.size(); ++i) {
    const Eigen::VectorXd& s = fused.emplace_back(fused_scores(h.scores[i], h.head_probabilities[i], c.fusion_head_share));
    const int winner = argmax(s);
    double second = 0;
    for (int k = 0; k < categories; ++k)
      if (k != winner) second = std::max(second, s[k]);
    const bool right = winner == h.truths[i];
    decisions.push_back({s[winner] - second, right});
    correct += right;
    h.winners.push_back(winner);
  }
  c.held_out = decisions.size();
  c.held_out_accuracy = double(correct) / double(decisions.size());
  c.settle_margin = settle_margin(std::move(decisions), precision, 20);
  calibrate_probabilities(c, fused, h.truths, precision);
}

// Per component, each reference of the model's own stage (which learnt every row): whether it is a whole
// cloud, and its training object.
void model_references(Calibration& c, const ModelImpl& impl, const std::vector<MethodId>& parts,
                      const CalibrationRows& rows) {
  for (MethodId m : parts) {
    std::vector<Eigen::Index> all(rows.labels.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Eigen::Index>(i);
    const DecisionRule kind = impl.stages[static_cast<int>(m)]->kind;
    c.reference_whole.push_back(whole_references(kind, rows.whole, all));
    c.reference_object.push_back(object_references(kind, rows.objects, all));
  }
}

}  // namespace

Calibration calibrate(const ModelImpl& impl, MethodId method, const CalibrationRows& rows, bool measure_novelty,
                      int threads, const CancelFn& cancel, const std::function<void(size_t, size_t)>& fold_done,
                      std::vector<Chi2Logistic>* fold_heads) {
  const TrainParams& p = impl.params;
  Calibration c;
  c.method = method;
  const int folds = p.calibration_folds;
  if (folds < 2 || !two_objects_per_category(rows.object_categories)) {
    if (fold_heads) fold_heads->clear();  // no fold learns a head
    return c;
  }
  InnerFolds in{impl, rows};
  in.object_fold = calibration_folds(rows.object_categories, folds, p.seed + 101);
  in.parts = component_methods(impl, method);
  in.novelty_objects = objects_per_category(rows.labels, rows.objects, in.object_fold, folds, rows.categories,
                                            std::max(1, p.novelty_objects));
  in.with_head = method == MethodId::kFusion && impl.fusion_head.has_value() && !p.fusion_head_shares.empty();
  in.measure_novelty = measure_novelty;
  in.threads = threads;
  in.decided = decided_rows(rows.keys, p.calibration_queries, p.seed + 103);
  const std::vector<Chi2Logistic> starts = fold_heads ? std::move(*fold_heads) : std::vector<Chi2Logistic>{};
  in.head_starts = &starts;
  std::vector<std::optional<Chi2Logistic>> heads(static_cast<size_t>(folds));
  HeldOut held_out;
  for (int k = 0; k < folds; ++k) {
    if (cancel && cancel()) return c;  // the caller sees the cancel and stores nothing
    decide_held_out_fold(in, k, cancel, held_out, heads[static_cast<size_t>(k)]);
    if (fold_done) fold_done(static_cast<size_t>(k) + 1, static_cast<size_t>(folds));
  }
  if (fold_heads) {  // every fold's, or none
    fold_heads->clear();
    if (std::all_of(heads.begin(), heads.end(), [](const auto& h) { return h.has_value(); }))
      for (auto& h : heads) fold_heads->push_back(std::move(*h));
  }
  if (held_out.scores.empty()) return c;
  if (in.with_head) c.fusion_head_share = choose_head_share(p.fusion_head_shares, held_out, c.fusion_head_share);
  settle_on_held_out(c, held_out, rows.categories, p.settle_precision);
  if (measure_novelty) calibrate_novelty(c, held_out, in.parts.size(), rows.categories, p.known_acceptance);
  if (!c.novelty_scale.empty()) {
    c.novelty_objects = in.novelty_objects;
    model_references(c, impl, in.parts, rows);
  }
  return c;
}

}  // namespace glimpse
