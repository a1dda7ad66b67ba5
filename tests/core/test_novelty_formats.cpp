// "None of these" in models of older formats: each keeps computing novelty as its quantiles were taken
// (format 8: the larger of the two evidences; 5: the nearest reference alone; 4: not over the score), and
// format 3 holds none.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "format3.h"
#include "glimpse/learning/model.h"
#include "open_set.h"

namespace glimpse {
namespace {

using test::classify_all;
using test::open_set;
using test::OpenSet;

// ---- models of formats 5 and 4: novelty from the nearest reference alone (format 4's not over the score) ----

// The open set's model as format 6 read it: no logistic decision in the fusion (the mean of its
// components' scores), what every older format reads too, so their scores compare with it.
const Model& format_6() {
  static const Model m = [] {
    const OpenSet& s = open_set();
    auto six = deserialize(test::as_format_6(test::format_11_bytes(s.model), s.model.categories.size()));
    EXPECT_TRUE(six.ok()) << (six.ok() ? "" : six.error().message);
    return six.ok() ? *six : Model{};
  }();
  return m;
}

// A model of format 5 measured a cloud's distance to a category to its nearest reference alone: its
// quantiles were taken that way, so it must keep computing it that way.
TEST(Novelty, AModelOfFormat5KeepsTheNearestReferenceAlone) {
  const OpenSet& s = open_set();
  ASSERT_EQ(calibration(s.model).novelty_objects, std::vector<int>(2, 4));
  ASSERT_FALSE(calibration(s.model).reference_object.empty());
  auto back = deserialize(test::as_format_5(test::format_11_bytes(s.model), calibration(s.model)));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(calibration(*back).novelty_objects.empty());
  EXPECT_TRUE(calibration(*back).reference_object.empty());
  EXPECT_EQ(calibration(*back).novelty_quantiles, calibration(s.model).novelty_quantiles);
  size_t differ = 0;
  std::vector<TrainingCloud> clouds = s.known;
  clouds.insert(clouds.end(), s.unknown.begin(), s.unknown.end());
  for (const TrainingCloud& t : clouds) {
    auto a = classify(format_6(), t.cloud), b = classify(*back, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
    ASSERT_TRUE(std::isfinite(b->novelty));
    // Several objects' mean is at least the nearest one's: the nearest reference alone is never farther.
    ASSERT_EQ(a->category_novelty.size(), b->category_novelty.size());
    for (size_t k = 0; k < a->category_novelty.size(); ++k) {
      EXPECT_LE(b->category_novelty[k], a->category_novelty[k] * (1 + 1e-9));
      differ += b->category_novelty[k] < a->category_novelty[k] * (1 - 1e-6);
    }
  }
  EXPECT_GT(differ, 0u);  // the known clouds' (the cans' are all outside PCA's span: the residual decides)
}

// Format 8 and older took their quantiles on the larger of the two evidences (the distance to the
// category, what PCA leaves out), not their sum: read so, a model keeps that, with the same scores.
TEST(Novelty, AModelOfFormat8KeepsTheLargerOfTheTwoEvidences) {
  const OpenSet& s = open_set();
  ASSERT_TRUE(calibration(s.model).novelty_adds_evidence);
  auto nine = deserialize(test::as_format_9(test::format_11_bytes(s.model)));  // no prefix either, as format 8
  auto eight = deserialize(test::as_format_8(test::format_11_bytes(s.model)));
  ASSERT_TRUE(eight.ok() && nine.ok()) << eight.error().message;
  EXPECT_FALSE(calibration(*eight).novelty_adds_evidence);
  EXPECT_EQ(calibration(*eight).novelty_quantiles, calibration(s.model).novelty_quantiles);
  size_t differ = 0;
  std::vector<TrainingCloud> clouds = s.known;
  clouds.insert(clouds.end(), s.unknown.begin(), s.unknown.end());
  for (const TrainingCloud& t : clouds) {
    auto a = classify(*nine, t.cloud), b = classify(*eight, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
    ASSERT_EQ(a->category_novelty.size(), b->category_novelty.size());
    for (size_t k = 0; k < a->category_novelty.size(); ++k) {
      // Of two non-negative evidences the larger is at most their sum and at least half of it.
      EXPECT_LE(b->category_novelty[k], a->category_novelty[k] * (1 + 1e-9));
      EXPECT_GE(2 * b->category_novelty[k], a->category_novelty[k] * (1 - 1e-9));
      differ += b->category_novelty[k] < a->category_novelty[k] * (1 - 1e-6);
    }
  }
  EXPECT_GT(differ, 0u);
  // The combination byte that ends a format-10 payload is 0 or 1; anything else is damage.
  std::vector<uint8_t> bytes = test::as_format_10(test::format_11_bytes(s.model));
  ASSERT_EQ(bytes[bytes.size() - 5], 1);
  bytes[bytes.size() - 5] = 2;
  auto damaged = test::read_as_format(bytes, 10);
  ASSERT_FALSE(damaged.ok());
  EXPECT_NE(damaged.error().message.find("novelty combination"), std::string::npos) << damaged.error().message;
}

// Format 4's quantiles were taken on novelty without the division by the score (and from the nearest
// reference, as format 5): the same scales, the novelty of every cloud that of format 5 times its
// winner's score, the same scores and winners.
TEST(Novelty, AModelOfFormat4KeepsItsNoveltyWithoutTheScore) {
  const OpenSet& s = open_set();
  ASSERT_TRUE(calibration(s.model).novelty_over_score);
  const Calibration& c = calibration(s.model);
  auto five = deserialize(test::as_format_5(test::format_11_bytes(s.model), c));
  auto back = deserialize(test::as_format_4(test::format_11_bytes(s.model), c));
  ASSERT_TRUE(back.ok() && five.ok()) << back.error().message;
  EXPECT_FALSE(calibration(*back).novelty_over_score);
  EXPECT_EQ(calibration(*back).novelty_quantiles, calibration(s.model).novelty_quantiles);
  for (const TrainingCloud& t : s.unknown) {
    auto a = classify(*five, t.cloud), b = classify(*back, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
    ASSERT_TRUE(std::isfinite(a->novelty) && std::isfinite(b->novelty));
    EXPECT_NEAR(b->novelty, a->novelty * a->scores[static_cast<size_t>(a->winner)], 1e-9 * a->novelty);
  }
}

// ---- a model of format 3, which holds no novelty ----

TEST(Novelty, AModelOfFormat3ReadsWithoutNovelty) {
  const OpenSet& s = open_set();
  const std::vector<uint8_t> old = test::as_format_3(test::format_11_bytes(s.model), calibration(s.model));
  auto back = deserialize(old);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(calibration(*back).novelty_scale.empty());
  EXPECT_TRUE(std::isnan(calibration(*back).novelty_threshold));
  EXPECT_EQ(calibration(*back).settle_margin, calibration(s.model).settle_margin);  // the rest reads the same
  for (const TrainingCloud& t : s.unknown) {
    auto a = classify(format_6(), t.cloud), b = classify(*back, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
    EXPECT_TRUE(std::isnan(b->novelty));
    EXPECT_FALSE(b->unknown);  // never unknown by novelty ...
    ASSERT_TRUE(set_known_acceptance(*back, *b, 0.5).ok());
    EXPECT_FALSE(b->unknown);
  }
  Cloud plane;  // ... but what a method cannot judge still is
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) plane.points.emplace_back(0.005f * float(i), 0.005f * float(j), 0.f);
  auto c = classify(*back, plane, MethodId::kBoK);
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_TRUE(c->unknown);
  // Written again, it is a format-4 model with no novelty calibration, and reads back the same.
  auto again = deserialize(serialize(*back));
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_TRUE(calibration(*again).novelty_scale.empty());
}

}  // namespace
}  // namespace glimpse
