// A cloud's scores under a model (sec. 3.3, 4): each base method's global histogram (BoK, BoG, KGH over
// the keypoint codebooks; VFH, ESF, USH and the size as computed), the decision stages' scores and
// nearest references, and the fusion's mean with its logistic decision's share.
#include "glimpse/learning/scores.h"

#include <algorithm>
#include <cmath>

#include "glimpse/learning/novelty.h"
#include "glimpse/random.h"
#include "glimpse/threads.h"

namespace glimpse {

Eigen::VectorXd method_histogram(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  const TrainParams& p = impl.params;
  const int up_to = p.normalise_up_to_keypoints;
  const bool normalise = p.normalise_histograms && up_to <= 0;
  // sec. 4: counts divided by min(count, count at up_to keypoints).
  auto early = [&](Eigen::VectorXd h, double count, double count_at_up_to) {
    if (up_to > 0 && count > 0) h /= std::min(count, count_at_up_to);
    return h;
  };
  const double n = static_cast<double>(up_to);
  switch (method) {
    case MethodId::kBoK:
      return early(p.bok_soft_words > 1
                       ? soft_bag_of_keypoints(impl.bok, f.descriptors, p.bok_soft_words, normalise)
                       : bag_of_keypoints(keypoint_words(impl.bok, f.descriptors), p.bok_clusters, normalise),
                   static_cast<double>(f.descriptors.size()), n);
    case MethodId::kBoG: {
      const auto graphs = local_graphs(f.positions, keypoint_words(impl.bog, f.descriptors));
      return early(bag_of_graphs(graphs, impl.graphs, normalise), static_cast<double>(graphs.size()), n);
    }
    case MethodId::kKGH: {
      const double k = static_cast<double>(f.positions.size());
      return early(keypoint_global_histogram(f.positions, keypoint_words(impl.kgh, f.descriptors), p.kgh_clusters,
                                             p.kgh_distance_bins, impl.kgh_max_distance_m, normalise),
                   k * (k - 1), n * (n - 1));
    }
    case MethodId::kVFH: return f.vfh ? Eigen::VectorXd(f.vfh->cast<double>()) : Eigen::VectorXd::Zero(kVfhSize);
    case MethodId::kESF: return f.esf ? Eigen::VectorXd(f.esf->cast<double>()) : Eigen::VectorXd::Zero(kEsfSize);
    case MethodId::kUSH:
      return f.ush ? Eigen::VectorXd(f.ush->cast<double>()) : Eigen::VectorXd::Zero(kUprightHistogramSize);
    case MethodId::kSize: return f.size ? Eigen::VectorXd(f.size->cast<double>()) : Eigen::VectorXd::Zero(kVisibleSizeSize);
    case MethodId::kFusion: break;
  }
  return {};
}

std::vector<MethodId> fusion_head_methods(const ModelImpl& impl) {
  std::vector<MethodId> parts = component_methods(impl, MethodId::kFusion);
  std::erase(parts, MethodId::kSize);
  return parts;
}

Eigen::VectorXd fusion_head_features(const ModelImpl& impl, const std::function<Eigen::VectorXd(MethodId)>& histogram) {
  std::vector<Eigen::VectorXd> histograms;
  for (MethodId m : fusion_head_methods(impl)) histograms.push_back(histogram(m));
  return additive_chi2_features(histograms, impl.params.fusion_head.sample_steps, impl.params.fusion_head.sample_interval);
}

Eigen::MatrixXd fusion_head_rows(const ModelImpl& impl, const std::vector<Eigen::MatrixXd>& histograms,
                                 const std::vector<Eigen::Index>& rows, int threads) {
  const std::vector<MethodId> parts = fusion_head_methods(impl);
  if (parts.empty()) return {};
  const Eigen::Index n = rows.empty() ? histograms[static_cast<size_t>(parts.front())].rows() : static_cast<Eigen::Index>(rows.size());
  auto features = [&](Eigen::Index i) {
    const Eigen::Index r = rows.empty() ? i : rows[static_cast<size_t>(i)];
    return fusion_head_features(impl, [&](MethodId m) { return Eigen::VectorXd(histograms[static_cast<size_t>(m)].row(r).transpose()); });
  };
  if (n == 0) return {};
  const Eigen::VectorXd first = features(0);
  Eigen::MatrixXd out(n, first.size());
  out.row(0) = first.transpose();
#pragma omp parallel for num_threads(threads > 0 ? threads : omp_get_max_threads()) schedule(static, 64)
  for (Eigen::Index i = 1; i < n; ++i) out.row(i) = features(i).transpose();
  return out;
}

std::vector<uint8_t> fusion_head_learns(const std::vector<int>& labels, const std::vector<uint64_t>& keys,
                                        int categories, int per_category, uint64_t seed) {
  std::vector<uint8_t> learns(labels.size(), 1);
  if (per_category <= 0) return learns;
  std::vector<std::vector<std::pair<uint64_t, size_t>>> by_category(static_cast<size_t>(categories));
  for (size_t i = 0; i < labels.size(); ++i)
    by_category[static_cast<size_t>(labels[i])].push_back({splitmix64(seed, keys[i]), i});
  for (auto& rows : by_category) {
    if (rows.size() <= static_cast<size_t>(per_category)) continue;
    std::nth_element(rows.begin(), rows.begin() + per_category, rows.end());
    for (size_t k = static_cast<size_t>(per_category); k < rows.size(); ++k) learns[rows[k].second] = 0;
  }
  return learns;
}

Eigen::VectorXd fused_scores(const Eigen::VectorXd& mean, const Eigen::VectorXd& probabilities, double share) {
  if (!(share > 0) || probabilities.size() != mean.size()) return mean;
  return (1 - share) * mean + share * probabilities;
}

namespace {
// The mean of `parts`' decision stages' scores of `f`; with `nearest`, each component's nearest
// references too.
Eigen::VectorXd component_scores(const ModelImpl& impl, const std::vector<MethodId>& parts, const CloudFeatures& f,
                                 std::vector<NearestReferences>* nearest) {
  const Calibration& cal = impl.calibration;
  Eigen::VectorXd scores;
  for (size_t j = 0; j < parts.size(); ++j) {
    const MethodId m = parts[j];
    // sec. 4: early in the exploration (fewer than normalise_up_to_keypoints keypoints) the words'
    // proportions are compared, the references' too; later the counts.
    const int up_to = impl.params.normalise_up_to_keypoints;
    const bool early = up_to > 0 && (m == MethodId::kBoK || m == MethodId::kKGH) &&
                       f.descriptors.size() < static_cast<size_t>(up_to);
    StageScores s = decide_with_distances(*impl.stages[static_cast<int>(m)], method_histogram(impl, m, f), early);
    scores = scores.size() ? Eigen::VectorXd(scores + s.scores) : s.scores;
    if (nearest) {
      const std::vector<uint32_t> none;
      const std::vector<uint32_t>& objects = j < cal.reference_object.size() ? cal.reference_object[j] : none;
      nearest->push_back(nearest_references(*impl.stages[static_cast<int>(m)], std::move(s), cal.reference_whole[j],
                                            objects, cal.novelty_objects));
    }
  }
  return scores / static_cast<double>(std::max<size_t>(1, parts.size()));
}

// A method's mean score over its components' decision stages and, with `with_novelty` and a calibrated
// novelty, how novel the cloud is to each category (joined by its top-down prefix's, as calibrated).
MethodDecision stage_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f, bool with_novelty) {
  const std::vector<MethodId> parts = component_methods(impl, method);
  const Calibration& cal = impl.calibration;
  const bool calibrated =
      with_novelty && cal.method == method && !cal.novelty_scale.empty() && cal.reference_whole.size() == parts.size();
  MethodDecision out;
  std::vector<NearestReferences> nearest;
  out.scores = component_scores(impl, parts, f, calibrated ? &nearest : nullptr);
  // Novelty from the nearest references and their scores alone: the logistic decision is as sure of a
  // cloud far from everything learnt as of a known one (a logistic score grows away from the boundary).
  if (!calibrated) return out;
  out.novelty = category_novelty(cal, nearest, out.scores);
  if (impl.params.novelty_prefix > 0 && f.top_prefix) {
    std::vector<NearestReferences> prefix_nearest;
    const Eigen::VectorXd prefix_scores = component_scores(impl, parts, *f.top_prefix, &prefix_nearest);
    out.novelty = joint_novelty(out.novelty, category_novelty(cal, prefix_nearest, prefix_scores));
  }
  return out;
}
}  // namespace

MethodDecision method_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  MethodDecision out = stage_decision(impl, method, f, !impl.novelty);
  // Trained with augmented clouds: novelty from the model of the clouds given as they are.
  if (impl.novelty) out.novelty = stage_decision(*impl.novelty, method, f, true).novelty;
  const double share = impl.calibration.fusion_head_share;
  if (method == MethodId::kFusion && impl.fusion_head && share > 0) {
    const Eigen::VectorXd features =
        fusion_head_features(impl, [&](MethodId m) { return method_histogram(impl, m, f); });
    out.scores = fused_scores(out.scores, chi2_logistic_probabilities(*impl.fusion_head, features), share);
  }
  return out;
}

Eigen::VectorXd method_scores(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  return method_decision(impl, method, f).scores;
}

NearestReferences nearest_references(const DecisionStage& stage, StageScores&& s,
                                     const std::vector<uint8_t>& reference_whole,
                                     const std::vector<uint32_t>& reference_object, const std::vector<int>& objects) {
  NearestReferences n;
  n.distance = std::move(s.nearest_distance);
  if (std::any_of(objects.begin(), objects.end(), [](int k) { return k > 1; }))
    if (Eigen::VectorXd d = nearest_objects_distance(stage, s.distance, reference_object, objects); d.size()) n.distance = std::move(d);
  n.residual = s.residual;
  n.whole.assign(static_cast<size_t>(n.distance.size()), 1);
  for (Eigen::Index k = 0; k < s.nearest_reference.size() && k < n.distance.size(); ++k) {
    const int r = s.nearest_reference[k];
    if (r >= 0 && static_cast<size_t>(r) < reference_whole.size()) n.whole[static_cast<size_t>(k)] = reference_whole[static_cast<size_t>(r)] ? 1 : 0;
  }
  return n;
}

}  // namespace glimpse
