// Calibrated class probabilities: a decision's scores (a softmin over distances, or the fusion's mean)
// turned into probabilities that mean what they say, by one temperature fitted at training time on the
// model's held-out decisions (temperature scaling), and how well a set of probabilities keeps its word.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <vector>

#include "glimpse/features/methods.h"

namespace glimpse {

struct Calibration;  // model.h

// Scores raised to 1 / temperature and renormalised: p_k = s_k^(1/T) / sum_j s_j^(1/T) (a softmax of the
// log-scores over T). The order of the categories, and so the winner, never changes.
std::vector<double> temperature_probabilities(std::span<const double> scores, double temperature);

// The temperature whose probabilities give `truths` the least log loss over the held-out `scores`
// (one row per decision). 1 when there are none.
double fit_temperature(const std::vector<Eigen::VectorXd>& scores, const std::vector<int>& truths);

// The model's temperature (fit_temperature) and settle probability (the lowest winner's probability at
// which the held-out decisions are at least `precision` right, as settle_margin) from its held-out
// decisions' scores and truths.
void calibrate_probabilities(Calibration& calibration, const std::vector<Eigen::VectorXd>& scores,
                             const std::vector<int>& truths, double precision);

// A model's calibrated probabilities for `scores` of `method`: empty when the model has no temperature
// for it (only its calibrated default method has one; a model of format 10 or older has none).
std::vector<double> calibrated_probabilities(const Calibration& calibration, MethodId method,
                                             std::span<const double> scores);

// How well probabilities keep their word over decisions of known categories: the expected calibration
// error (the mean over `bins` equal bins of the winner's probability of |accuracy - mean probability|,
// weighted by the decisions in each), the mean log loss and the mean Brier score (sum over categories of
// (p - 1{truth})^2), with each bin's count, mean probability and accuracy (the reliability diagram).
struct ReliabilityBin {
  size_t decisions = 0;
  double mean_probability = 0;
  double accuracy = 0;
};
struct ProbabilityQuality {
  size_t decisions = 0;
  double expected_calibration_error = 0;
  double log_loss = 0;
  double brier = 0;
  std::vector<ReliabilityBin> bins;
};
// One row of `probabilities` per decision, with its truth (an index into the row).
ProbabilityQuality probability_quality(const std::vector<std::vector<double>>& probabilities,
                                       const std::vector<int>& truths, size_t bins = 10);

}  // namespace glimpse
