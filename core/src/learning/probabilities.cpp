// Temperature scaling of a decision's scores (Guo et al. 2017, "On calibration of modern neural
// networks"), fitted on held-out decisions by their log loss, and the reliability of probabilities.
#include "glimpse/learning/probabilities.h"

#include <algorithm>
#include <cmath>

#include "glimpse/learning/model.h"

namespace glimpse {

namespace {
constexpr double kFloor = 1e-12;  // a score of 0 is a log-score of log(1e-12), not -inf

// Mean log loss of the truths at inverse temperature `beta`.
double log_loss_at(const std::vector<Eigen::VectorXd>& scores, const std::vector<int>& truths, double beta) {
  double sum = 0;
  for (size_t i = 0; i < scores.size(); ++i) {
    const Eigen::ArrayXd logits = beta * scores[i].array().max(kFloor).log();
    const double top = logits.maxCoeff();
    sum += top + std::log((logits - top).exp().sum()) - logits[truths[i]];
  }
  return sum / double(std::max<size_t>(1, scores.size()));
}
}  // namespace

std::vector<double> temperature_probabilities(std::span<const double> scores, double temperature) {
  std::vector<double> p(scores.size());
  if (scores.empty() || !(temperature > 0)) return p;
  for (size_t k = 0; k < scores.size(); ++k) p[k] = std::log(std::max(scores[k], kFloor)) / temperature;
  const double top = *std::max_element(p.begin(), p.end());
  double sum = 0;
  for (double& v : p) sum += v = std::exp(v - top);
  for (double& v : p) v /= sum;
  return p;
}

double fit_temperature(const std::vector<Eigen::VectorXd>& scores, const std::vector<int>& truths) {
  if (scores.empty() || scores.size() != truths.size()) return 1.0;
  // The log loss is convex in the inverse temperature: a golden-section search over [0.2, 50] (T from
  // 0.02 to 5) finds its minimum to well under a thousandth.
  const double golden = (std::sqrt(5.0) - 1) / 2;
  double lo = std::log(0.2), hi = std::log(50.0);
  double a = hi - golden * (hi - lo), b = lo + golden * (hi - lo);
  double fa = log_loss_at(scores, truths, std::exp(a)), fb = log_loss_at(scores, truths, std::exp(b));
  for (int it = 0; it < 60; ++it) {
    if (fa <= fb) {
      hi = b, b = a, fb = fa;
      a = hi - golden * (hi - lo);
      fa = log_loss_at(scores, truths, std::exp(a));
    } else {
      lo = a, a = b, fa = fb;
      b = lo + golden * (hi - lo);
      fb = log_loss_at(scores, truths, std::exp(b));
    }
  }
  return 1.0 / std::exp((lo + hi) / 2);
}

void calibrate_probabilities(Calibration& c, const std::vector<Eigen::VectorXd>& scores, const std::vector<int>& truths,
                             double precision) {
  c.probability_temperature = fit_temperature(scores, truths);
  std::vector<std::pair<double, bool>> decisions;
  for (size_t i = 0; i < scores.size() && i < truths.size(); ++i) {
    const std::vector<double> p = temperature_probabilities({scores[i].data(), size_t(scores[i].size())}, c.probability_temperature);
    const size_t winner = static_cast<size_t>(std::max_element(p.begin(), p.end()) - p.begin());
    decisions.push_back({p[winner], winner == static_cast<size_t>(truths[i])});
  }
  c.settle_probability = settle_margin(std::move(decisions), precision, 20);
}

std::vector<double> calibrated_probabilities(const Calibration& calibration, MethodId method,
                                             std::span<const double> scores) {
  if (calibration.method != method || !(calibration.probability_temperature > 0)) return {};
  return temperature_probabilities(scores, calibration.probability_temperature);
}

ProbabilityQuality probability_quality(const std::vector<std::vector<double>>& probabilities,
                                       const std::vector<int>& truths, size_t bins) {
  ProbabilityQuality q;
  q.bins.resize(std::max<size_t>(1, bins));
  std::vector<double> right(q.bins.size(), 0);
  for (size_t i = 0; i < probabilities.size() && i < truths.size(); ++i) {
    const std::vector<double>& p = probabilities[i];
    if (p.empty() || truths[i] < 0 || static_cast<size_t>(truths[i]) >= p.size()) continue;
    const size_t winner = static_cast<size_t>(std::max_element(p.begin(), p.end()) - p.begin());
    const size_t bin = std::min(q.bins.size() - 1, static_cast<size_t>(p[winner] * double(q.bins.size())));
    ++q.bins[bin].decisions;
    q.bins[bin].mean_probability += p[winner];
    right[bin] += winner == static_cast<size_t>(truths[i]);
    q.log_loss -= std::log(std::max(p[static_cast<size_t>(truths[i])], kFloor));
    for (size_t k = 0; k < p.size(); ++k) q.brier += std::pow(p[k] - (k == static_cast<size_t>(truths[i]) ? 1.0 : 0.0), 2);
    ++q.decisions;
  }
  if (!q.decisions) return q;
  for (size_t b = 0; b < q.bins.size(); ++b) {
    ReliabilityBin& bin = q.bins[b];
    if (!bin.decisions) continue;
    q.expected_calibration_error += std::abs(right[b] - bin.mean_probability) / double(q.decisions);
    bin.mean_probability /= double(bin.decisions);
    bin.accuracy = right[b] / double(bin.decisions);
  }
  q.log_loss /= double(q.decisions);
  q.brier /= double(q.decisions);
  return q;
}

}  // namespace glimpse
