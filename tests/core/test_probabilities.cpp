// Calibrated probabilities: temperature scaling keeps the decision and sums to one, the fitted
// temperature is the one that made the truths, the reliability measures count what they say, and a
// trained model carries its temperature into every answer, its bytes and its streams.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "glimpse/learning/classify.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/session/session.h"
#include "format3.h"
#include "open_set.h"

namespace glimpse {
namespace {

TEST(TemperatureProbabilities, KeepTheOrderAndSumToOne) {
  const std::vector<double> scores = {0.5, 0.3, 0.2, 0.0};
  for (double t : {0.1, 0.5, 1.0, 3.0}) {
    const std::vector<double> p = temperature_probabilities(scores, t);
    ASSERT_EQ(p.size(), 4u);
    EXPECT_NEAR(std::accumulate(p.begin(), p.end(), 0.0), 1.0, 1e-12);
    EXPECT_GT(p[0], p[1]);
    EXPECT_GT(p[1], p[2]);
    EXPECT_GE(p[2], p[3]);
  }
  const std::vector<double> same = temperature_probabilities(scores, 1.0);
  for (size_t k = 0; k < 3; ++k) EXPECT_NEAR(same[k], scores[k], 1e-9);
  // Below 1 sharpens: 0.5 and 0.3 at T 0.5 are 0.25 / 0.38 and 0.09 / 0.38.
  EXPECT_NEAR(temperature_probabilities(scores, 0.5)[0], 0.25 / 0.38, 1e-6);
  EXPECT_TRUE(temperature_probabilities({}, 0.5).empty());
}

// Truths drawn from p = s^(1/T) for T = 0.25: the log loss's minimum is near 0.25, and the probabilities
// at the fitted temperature keep their word where the raw scores (T = 1) promise too little.
TEST(FitTemperature, RecoversTheTemperatureThatMadeTheTruths) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.05, 1.0);
  std::vector<Eigen::VectorXd> scores;
  std::vector<int> truths;
  std::vector<std::vector<double>> raw, fitted;
  for (int i = 0; i < 4000; ++i) {
    Eigen::VectorXd s(5);
    for (int k = 0; k < 5; ++k) s[k] = u(rng);
    s /= s.sum();
    const std::vector<double> p = temperature_probabilities({s.data(), 5}, 0.25);
    truths.push_back(std::discrete_distribution<int>(p.begin(), p.end())(rng));
    scores.push_back(s);
  }
  const double t = fit_temperature(scores, truths);
  EXPECT_NEAR(t, 0.25, 0.02);
  for (const Eigen::VectorXd& s : scores) {
    raw.emplace_back(s.data(), s.data() + 5);
    fitted.push_back(temperature_probabilities({s.data(), 5}, t));
  }
  EXPECT_LT(probability_quality(fitted, truths).expected_calibration_error, 0.03);
  EXPECT_GT(probability_quality(raw, truths).expected_calibration_error, 0.15);
  EXPECT_EQ(fit_temperature({}, {}), 1.0);
}

TEST(ProbabilityQuality, CountsWhatItSays) {
  // Two decisions at 0.9 (one right), one at 0.6 (right); 10 bins.
  const std::vector<std::vector<double>> p = {{0.9, 0.1}, {0.9, 0.1}, {0.4, 0.6}};
  const ProbabilityQuality q = probability_quality(p, {0, 1, 1});
  EXPECT_EQ(q.decisions, 3u);
  ASSERT_EQ(q.bins.size(), 10u);
  EXPECT_EQ(q.bins[9].decisions, 2u);
  EXPECT_NEAR(q.bins[9].mean_probability, 0.9, 1e-12);
  EXPECT_NEAR(q.bins[9].accuracy, 0.5, 1e-12);
  EXPECT_EQ(q.bins[6].decisions, 1u);
  // |1 - 1.8| / 3 + |1 - 0.6| / 3
  EXPECT_NEAR(q.expected_calibration_error, (0.8 + 0.4) / 3, 1e-12);
  EXPECT_NEAR(q.log_loss, (-std::log(0.9) - std::log(0.1) - std::log(0.6)) / 3, 1e-12);
  EXPECT_NEAR(q.brier, (0.02 + 1.62 + 0.32) / 3, 1e-12);
  // Unknown truths (-1) and empty rows are left out.
  EXPECT_EQ(probability_quality({{0.5, 0.5}, {}}, {-1, 0}).decisions, 0u);
}

// The open-set model (balls and boxes, the fusion the default): its default method answers with
// probabilities of its temperature, other methods with scores only; bytes keep the temperature, and a
// model of format 10 reads without one.
TEST(Probabilities, EveryAnswerOfTheDefaultMethodCarriesThem) {
  const test::OpenSet& s = test::open_set();
  const Calibration& c = calibration(s.model);
  ASSERT_GT(c.probability_temperature, 0.0);
  EXPECT_LT(c.probability_temperature, 5.0);
  EXPECT_GT(c.settle_probability, 0.2);  // above chance of two categories' probability, at most 1
  EXPECT_LE(c.settle_probability, 1.0 + 1e-6);
  for (const TrainingCloud& cloud : s.known) {
    auto r = classify(s.model, cloud.cloud);
    ASSERT_TRUE(r.ok()) << r.error().message;
    ASSERT_EQ(r->probabilities.size(), r->scores.size());
    EXPECT_EQ(r->probabilities, temperature_probabilities(r->scores, c.probability_temperature));
    EXPECT_EQ(std::max_element(r->probabilities.begin(), r->probabilities.end()) - r->probabilities.begin(), r->winner);
    auto vfh = classify(s.model, cloud.cloud, MethodId::kVFH);
    ASSERT_TRUE(vfh.ok());
    EXPECT_TRUE(vfh->probabilities.empty());
  }
  auto again = deserialize(serialize(s.model));
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(calibration(*again).probability_temperature, c.probability_temperature);
  EXPECT_EQ(calibration(*again).settle_probability, c.settle_probability);
  auto ten = deserialize(test::as_format_10(test::format_11_bytes(s.model)));
  ASSERT_TRUE(ten.ok()) << ten.error().message;
  EXPECT_EQ(calibration(*ten).probability_temperature, 0.0);
  EXPECT_EQ(calibration(*ten).settle_probability, 0.0);
  auto old = classify(*ten, s.known.front().cloud);
  ASSERT_TRUE(old.ok());
  EXPECT_TRUE(old->probabilities.empty());
}

TEST(Probabilities, AStreamsDecisionsCarryThoseOfItsSmoothedScores) {
  const test::OpenSet& s = test::open_set();
  const double t = calibration(s.model).probability_temperature;
  auto session = ScanSession::create(std::make_shared<const Model>(s.model));
  ASSERT_TRUE(session.ok()) << session.error().message;
  const Cloud& cloud = s.known.front().cloud;
  const size_t half = cloud.points.size() / 2;
  Cloud a = cloud, b = cloud;
  a.points.resize(half);
  b.points.erase(b.points.begin(), b.points.begin() + static_cast<std::ptrdiff_t>(half));
  for (const Cloud* chunk : {&a, &b}) {
    auto d = (*session)->add(*chunk);
    ASSERT_TRUE(d.ok()) << d.error().message;
    if (d->winner < 0) continue;
    EXPECT_EQ(d->probabilities, temperature_probabilities(d->scores, t));
  }
  auto final = (*session)->finish();
  ASSERT_TRUE(final.ok()) << final.error().message;
  auto whole = classify(s.model, cloud);
  ASSERT_TRUE(whole.ok());
  EXPECT_EQ(final->probabilities, whole->probabilities);
}

}  // namespace
}  // namespace glimpse
