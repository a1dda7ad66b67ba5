// Calibrated probabilities on held-out zoo objects: each model fits its temperature on inner folds of
// its own training objects, and its probabilities keep their word on the objects its fold held out,
// far better than the raw scores; the report's section and reliability diagram show them, and its
// streams settle on each model's settle probability.
#include <gtest/gtest.h>

#include <iostream>

#include "glimpse/lab/evaluation.h"
#include "glimpse/learning/probabilities.h"
#include "reduced_params.h"

namespace glimpse {
namespace {

TEST(RunEvaluation, ProbabilitiesKeepTheirWordOnHeldOutZooObjects) {
  EvalParams p = testing::reduced_params();
  p.methods = {MethodId::kFusion};
  p.stages = {{StageKind::kFull, 0}, {StageKind::kFraction, 0.2}};
  p.explore_max_keypoints = 0;
  p.stream_chunk_fraction = 0.1;
  p.matrix.clear();
  auto r = run_evaluation(zoo_objects(16, 5), p, "zoo");
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->probability_temperatures.size(), 2u);
  for (double t : r->probability_temperatures) EXPECT_GT(t, 0.0);
  ASSERT_EQ(r->settle_probabilities.size(), 2u);
  for (double s : r->settle_probabilities) EXPECT_GT(s, 0.2);
  std::vector<std::vector<double>> probabilities, scores;
  std::vector<int> truths;
  for (const StageDecision& d : r->decisions) {
    ASSERT_EQ(d.probabilities.size(), d.scores.size());
    probabilities.push_back(d.probabilities);
    scores.push_back(d.scores);
    truths.push_back(d.truth);
  }
  const ProbabilityQuality calibrated = probability_quality(probabilities, truths);
  const ProbabilityQuality raw = probability_quality(scores, truths);
  std::cout << "zoo 16 per category, 2 folds: " << calibrated.decisions << " decisions, temperatures "
            << r->probability_temperatures[0] << ", " << r->probability_temperatures[1] << "; ECE "
            << raw.expected_calibration_error << " -> " << calibrated.expected_calibration_error << ", log loss "
            << raw.log_loss << " -> " << calibrated.log_loss << "\n";
  EXPECT_EQ(calibrated.decisions, 16u * 5 * 3 * 2);
  // Measured (zoo 16 per category, seed 5, 2 folds, 3 views of 3000 points, full and 20 %; temperatures
  // 0.114 and 0.157): ECE 0.550 -> 0.019, log loss 0.852 -> 0.050.
  EXPECT_LE(calibrated.expected_calibration_error, 0.025);
  EXPECT_GT(raw.expected_calibration_error, 0.4);
  EXPECT_LT(calibrated.log_loss, raw.log_loss);
  const std::string report = markdown_report(*r);
  EXPECT_NE(report.find("## Calibrated probabilities (Fusion)"), std::string::npos);
  // Its streams settle on each model's settle probability, and the report says so.
  EXPECT_NE(report.find("Settle probability per model:"), std::string::npos);
  EXPECT_NE(report.find("confidence >= the calibrated probability"), std::string::npos);
  const std::string svg = reliability_svg(*r);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("class=\"bin\""), std::string::npos);
  EXPECT_NE(decisions_csv(*r).find(",probability_chair"), std::string::npos);
}

}  // namespace
}  // namespace glimpse
