// A learnt decision over the fusion's histograms, beside its nearest-reference scores: the histograms
// mapped so that a dot product approximates the additive chi-squared kernel (Vedaldi & Zisserman 2012,
// "Efficient additive kernels via explicit feature maps"), then one-vs-rest L2-regularised logistic
// regression (LIBLINEAR). Nearest references remember every training view; this weighs every bin over
// all of them, so it holds up where an object of another modeller has no close neighbour.
#pragma once

#include <string>
#include <vector>

#include "glimpse/expected.h"
#include <Eigen/Core>

namespace glimpse {

struct Chi2LogisticParams {
  double c = 10;             // inverse regularisation strength (LIBLINEAR's C); TrainParams turns it off (0)
  int sample_steps = 2;      // terms of the feature map per bin: 2 x steps - 1
  double sample_interval = 0.5;
  // LIBLINEAR's stopping tolerance (eps): the solver stops once the gradient's norm is at most this share
  // of its norm at zero (times the smaller side's share of the rows). Against 1e-4, 1e-3 moves 20 of
  // SHREC -> PSB's 2700 fusion winners and takes PSB -> SHREC's run 0.91x the time (docs/notebook.md,
  // "Run time"); LIBLINEAR's default is 1e-2.
  double tolerance = 1e-3;
};

struct Chi2Logistic {
  int sample_steps = 2;
  double sample_interval = 0.5;
  Eigen::MatrixXd weights;  // categories x mapped features
  Eigen::VectorXd bias;     // per category
};

// Each histogram divided by its L1 mass (negative bins as 0), mapped, and the maps concatenated. A
// histogram of no mass maps to zeros.
Eigen::VectorXd additive_chi2_features(const std::vector<Eigen::VectorXd>& histograms, int sample_steps,
                                       double sample_interval);

// Rows of `features` (additive_chi2_features) with `labels` in [0, categories), every category present.
// Deterministic (LIBLINEAR's primal trust-region solver draws nothing at random), whatever the number
// of threads (0: all cores) the categories' one-vs-rest problems are shared among. `start`, a head of
// the same categories and features (another fit on related rows), is where the solver starts instead
// of zero: it stops at the same tolerance (a share of the gradient at zero), in fewer steps.
Expected<Chi2Logistic> fit_chi2_logistic(const Eigen::MatrixXd& features, const std::vector<int>& labels, int categories,
                                         const Chi2LogisticParams& params, int threads = 1,
                                         const Chi2Logistic* start = nullptr);

// `head`, learnt over `from` categories, with its rows for `to` (by name): where a solver of `to`'s problem
// starts. A category `from` lacks takes its row of `others` (a head over `to`, of the same features) when
// given, else zero weights and bias (where a cold solver starts).
Chi2Logistic head_for_categories(const Chi2Logistic& head, const std::vector<std::string>& from,
                                 const std::vector<std::string>& to, const Chi2Logistic* others = nullptr);

// Per category, its one-vs-rest probability, normalised to sum to 1 (LIBLINEAR's predict_probability).
Eigen::VectorXd chi2_logistic_probabilities(const Chi2Logistic& head, const Eigen::VectorXd& features);

}  // namespace glimpse
