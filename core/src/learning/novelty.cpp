// "None of these" (docs/open-set.md): a cloud's novelty per category, joined with its top-down prefix's,
// against the threshold of an operating point, and the size rule.
#include "glimpse/learning/novelty.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace glimpse {

Eigen::VectorXd category_novelty(const Calibration& c, const std::vector<NearestReferences>& components,
                                 const Eigen::VectorXd& scores) {
  if (c.novelty_scale.empty() || c.novelty_scale.size() != components.size()) return {};
  const Eigen::Index categories = components.front().distance.size();
  const size_t n_cat = static_cast<size_t>(categories);
  Eigen::VectorXd near = Eigen::VectorXd::Zero(categories), outside = Eigen::VectorXd::Zero(categories);
  for (size_t j = 0; j < components.size(); ++j) {
    const std::vector<double>& scale = c.novelty_scale[j];
    const NearestReferences& n = components[j];
    if (n.distance.size() != categories || n.whole.size() != n_cat || scale.size() != 2 * n_cat + 2) return {};
    for (Eigen::Index k = 0; k < categories; ++k) {
      const size_t whole = n.whole[static_cast<size_t>(k)] ? 1 : 0;
      near[k] += n.distance[k] / scale[2 * static_cast<size_t>(k) + whole];
      outside[k] += n.residual / scale[2 * n_cat + whole];
    }
  }
  // Novel both ways, added: far from every reference of the category, and outside what training
  // histograms span (a model of format 8 or older: the larger).
  Eigen::VectorXd novelty = (c.novelty_adds_evidence ? Eigen::VectorXd(near + outside) : Eigen::VectorXd(near.cwiseMax(outside))) /
                            double(components.size());
  // ... and more so when the decision is torn between categories (its score for this one is low).
  if (c.novelty_over_score && scores.size() == categories) novelty.array() /= scores.array().max(1e-6);
  return novelty;
}

Eigen::VectorXd joint_novelty(const Eigen::VectorXd& whole, const Eigen::VectorXd& prefix) {
  if (prefix.size() != whole.size()) return whole;
  return whole.cwiseProduct(prefix).cwiseSqrt();
}

double novelty_threshold(const Calibration& c, double known_acceptance) {
  const std::vector<double>& q = c.novelty_quantiles;
  if (q.size() < 2 || !(known_acceptance > 0 && known_acceptance <= 1)) return std::numeric_limits<double>::quiet_NaN();
  // Linear between the stored quantiles.
  const double x = known_acceptance * double(q.size() - 1);
  const size_t lo = std::min(q.size() - 2, static_cast<size_t>(x));
  const double t = x - double(lo);
  return q[lo] + t * (q[lo + 1] - q[lo]);
}

std::string cannot_judge(MethodId method, const std::vector<MethodId>& components, const CloudFeatures& f) {
  // A keypoint histogram of too few keypoints is empty (BoG's graphs join 4 keypoints, KGH's pairs 2):
  // its nearest category is an accident. Fusion judges as long as one component can.
  auto blind = [&](MethodId m) {
    const size_t k = f.positions.size();
    return (m == MethodId::kBoK && k == 0) || (m == MethodId::kBoG && k < 4) || (m == MethodId::kKGH && k < 2);
  };
  if (components.empty() || !std::all_of(components.begin(), components.end(), blind)) return {};
  return std::to_string(f.positions.size()) + " keypoint" + (f.positions.size() == 1 ? "" : "s") + ": " +
         method_name(method) + " cannot judge this cloud (an empty histogram)";
}

namespace {

// `unknown` and its reason from the novelty at `threshold` (NaN: no novelty threshold, never unknown).
void judge_novelty(Classification& c, double threshold, double known_acceptance) {
  c.unknown = std::isfinite(threshold) && std::isfinite(c.novelty) && c.novelty > threshold;
  c.unknown_reason.clear();
  if (c.outside_learnt_sizes) {  // the reason a person can act on (a unit), whatever the novelty
    c.unknown = true;
    c.unknown_reason = "size far outside what the model learnt: " + c.warning;
  }
  if (!c.unknown || !c.unknown_reason.empty()) return;
  char why[200];
  std::snprintf(why, sizeof why,
                "novelty %.2f above %.2f, the threshold accepting %.1f %% of known clouds (held out in training)",
                c.novelty, threshold, 100 * known_acceptance);
  c.unknown_reason = why;
}

}  // namespace

void judge_unknown(const Model& model, const MethodDecision& decision, const CloudFeatures& f, Classification& c) {
  if (std::string why = cannot_judge(c.method, component_methods(*model.impl, c.method), f); !why.empty()) {
    c.novelty = std::numeric_limits<double>::quiet_NaN();
    c.unknown = true;
    c.unknown_reason = std::move(why);
    return;
  }
  c.category_novelty.assign(decision.novelty.data(), decision.novelty.data() + decision.novelty.size());
  if (decision.novelty.size() && c.winner >= 0) c.novelty = decision.novelty[c.winner];
  (void)set_known_acceptance(model, c, 0);  // 0 (the default) is always valid
}

void judge_cloud(const Model& model, const MethodDecision& decision, const CloudFeatures& f, const Cloud& points,
                 Classification& c) {
  c.frame_cut = frame_cut(points);
  c.warning = size_warning(model.stats, points);
  c.outside_learnt_sizes = !c.warning.empty();
  judge_unknown(model, decision, f, c);
}

Status set_known_acceptance(const Model& model, Classification& c, double known_acceptance) {
  if (!(known_acceptance >= 0 && known_acceptance <= 1))
    return invalid_argument("known acceptance must be in (0, 1] (0: the model's default), not " +
                            std::to_string(known_acceptance));
  if (c.unknown && !std::isfinite(c.novelty)) return {};  // the method cannot judge the cloud at all
  const Calibration& cal = novelty_calibration(model);
  const double a = known_acceptance > 0 ? known_acceptance : cal.known_acceptance;
  judge_novelty(c, cal.method == c.method ? novelty_threshold(cal, a) : std::numeric_limits<double>::quiet_NaN(), a);
  return {};
}

// ---- Classification ----------------------------------------------------------------------------

std::string size_warning(const TrainingSummary& stats, const Cloud& cloud) {
  if (!(stats.max_extent_m > 0) || cloud.points.empty()) return {};
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : cloud.points)
    if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const float extent = (hi - lo).maxCoeff();
  if (!std::isfinite(extent)) return {};
  char known[96];
  std::snprintf(known, sizeof known, "the model knows %.2g-%.2g m objects", stats.min_extent_m, stats.max_extent_m);
  char buf[256];
  if (extent > 4 * stats.max_extent_m) {
    const char* unit = extent > 300 * stats.max_extent_m ? "millimetres" : extent > 30 * stats.max_extent_m ? "centimetres" : "another unit";
    std::snprintf(buf, sizeof buf, "the cloud spans %.3g m, %s: %s? Clouds are in metres", extent, known, unit);
    return buf;
  }
  if (extent < stats.min_extent_m / 4 && !frame_cut(cloud).any()) {  // a cut cloud is part of its object
    std::snprintf(buf, sizeof buf, "the cloud spans only %.3g m, %s: another unit (clouds are in metres)?", extent, known);
    return buf;
  }
  return {};
}

}  // namespace glimpse
