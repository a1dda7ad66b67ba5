// "None of these": the novelty a model calibrates on held-out folds of its own training set, the
// operating point, what a method cannot judge, the top-down prefix and the novelty model (older formats:
// test_novelty_formats.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <cstring>
#include <iostream>
#include <random>

#include "glimpse/learning/metrics.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "format3.h"
#include "open_set.h"
#include "synthetic.h"

namespace glimpse {
namespace {

using test::classify_all;
using test::open_set;
using test::open_set_params;
using test::OpenSet;
using test::without;

TEST(Novelty, IsCalibratedOnHeldOutFoldsOfTheTrainingSet) {
  const Calibration& c = calibration(open_set().model);
  ASSERT_EQ(c.novelty_scale.size(), 2u);  // fusion of USH and VFH
  for (const auto& per : c.novelty_scale) {
    ASSERT_EQ(per.size(), 6u);  // ball, box, each against a prefix and a whole cloud; the PCA residual's two
    for (double s : per) EXPECT_GT(s, 0.0);
  }
  ASSERT_EQ(c.reference_whole.size(), 2u);
  for (const auto& flags : c.reference_whole) {
    EXPECT_GT(std::count(flags.begin(), flags.end(), 1), 0);  // the training views
    EXPECT_GT(std::count(flags.begin(), flags.end(), 0), 0);  // and their top-down prefixes
  }
  // Distances over several training objects of a category: every reference's object, numbered densely.
  // 6 objects of each category, 4 inner folds: an inner training fold holds 4 or 5 of them.
  EXPECT_EQ(c.novelty_objects, std::vector<int>(2, 4));
  ASSERT_EQ(c.reference_object.size(), 2u);
  for (size_t j = 0; j < 2; ++j) {
    const std::vector<uint32_t>& o = c.reference_object[j];
    ASSERT_EQ(o.size(), c.reference_whole[j].size());
    EXPECT_EQ(*std::max_element(o.begin(), o.end()) + 1, std::set<uint32_t>(o.begin(), o.end()).size());
  }
  ASSERT_EQ(c.novelty_quantiles.size(), kNoveltyQuantiles);
  EXPECT_TRUE(std::is_sorted(c.novelty_quantiles.begin(), c.novelty_quantiles.end()));
  EXPECT_DOUBLE_EQ(c.known_acceptance, 0.95);
  EXPECT_DOUBLE_EQ(c.novelty_threshold, novelty_threshold(c, 0.95));
  EXPECT_LE(novelty_threshold(c, 0.5), novelty_threshold(c, 0.95));
  EXPECT_LE(novelty_threshold(c, 0.95), novelty_threshold(c, 1.0));
  // Novelty adds two evidences, each over its typical held-out value: the median held-out known cloud is
  // near 2 (2.36 here: the decision's score divides it).
  EXPECT_GT(novelty_threshold(c, 0.5), 1.0);
  EXPECT_LT(novelty_threshold(c, 0.5), 4.0);
  EXPECT_TRUE(std::isnan(novelty_threshold(c, 0.0)));
  EXPECT_TRUE(std::isnan(novelty_threshold(Calibration{}, 0.95)));
}

// Cans were never learnt: their views must come out more novel than new balls' and boxes'. Measured
// (6 objects per category, 3 views, seed 1; tested on 5 new objects, 2 views each): AUROC 0.95; 19 of
// 20 known views accepted at the default operating point (95 % promised), 10 of 10 cans rejected (also
// with the top-down prefix's novelty joined to the cloud's, TrainParams::novelty_prefix). With the
// larger of novelty's two evidences, not their sum (format 8): 0.955, 16 of 20, 10 of 10. From
// the nearest reference alone (not a category's 4 nearest objects): 0.95, 17 of 20, 10 of 10. Without
// dividing novelty by the decision's score: AUROC 0.925, 18 of 20, 8 of 10; with calibration deciding the
// held-out views tilted (as they are learnt, not as they come): 0.975, 10 of 20, 10 of 10.
TEST(Novelty, TellsACategoryNeverLearntFromTheKnownOnes) {
  const OpenSet& s = open_set();
  std::vector<double> known, unknown;
  size_t accepted = 0, rejected = 0;
  for (const Classification& c : classify_all(s.model, s.known)) {
    ASSERT_TRUE(std::isfinite(c.novelty));
    known.push_back(c.novelty);
    accepted += !c.unknown;
  }
  for (const Classification& c : classify_all(s.model, s.unknown)) {
    ASSERT_TRUE(std::isfinite(c.novelty));
    unknown.push_back(c.novelty);
    rejected += c.unknown;
    EXPECT_GE(c.winner, 0);  // the winner stays the nearest known category
  }
  const double a = auroc(known, unknown);
  std::cout << "balls and boxes learnt, cans unknown: AUROC " << a << ", known accepted " << accepted << "/"
            << known.size() << ", cans rejected " << rejected << "/" << unknown.size() << "\n";
  EXPECT_GE(a, 0.93);  // measured 0.95
  EXPECT_GE(double(accepted) / double(known.size()), 0.9);  // measured 0.95
  EXPECT_GE(double(rejected) / double(unknown.size()), 0.9);  // measured 1.0
}

// What the issue names: a cloud in millimetres (a 100 m ball), a room's corner, a 2 m wavy sheet. Their
// histograms fall outside what the training histograms span (measured novelty 8.6-10.8, threshold 3.8;
// 8.5-10.5 and 4.0 without the top-down prefix's novelty; 5.2-6.3 and 2.3 with the larger of novelty's
// two evidences, not their sum).
TEST(Novelty, CloudsFarOutsideEverythingLearntAreUnknown) {
  const OpenSet& s = open_set();
  Cloud giant = s.known.front().cloud;
  for (Vec3& p : giant.points) p *= 1000.f;
  Cloud room;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 4);
  for (int i = 0; i < 4000; ++i) {
    const float x = u(rng), y = u(rng);
    room.points.emplace_back(x, y, 0.f);
    room.points.emplace_back(x, 0.f, 0.6f * u(rng));
    room.points.emplace_back(0.f, y, 0.6f * u(rng));
  }
  Cloud sheet;
  for (int i = 0; i < 70; ++i)
    for (int j = 0; j < 70; ++j)
      sheet.points.emplace_back(0.03f * float(i), 0.03f * float(j), 0.1f * std::sin(0.3f * float(i)) + 0.002f * float(j));
  for (const Cloud* cloud : {&giant, &room, &sheet}) {
    auto c = classify(s.model, *cloud);
    ASSERT_TRUE(c.ok()) << c.error().message;
    EXPECT_TRUE(c->unknown) << "novelty " << c->novelty << ", threshold " << calibration(s.model).novelty_threshold;
    EXPECT_GT(c->novelty, 1.5 * calibration(s.model).novelty_threshold);
    std::cout << "far outside: novelty " << c->novelty << ", threshold " << calibration(s.model).novelty_threshold << "\n";
  }
}

TEST(Novelty, TheOperatingPointMovesUnknownButNotTheWinner) {
  const OpenSet& s = open_set();
  size_t at_default = 0, at_half = 0, at_all = 0;
  for (Classification c : classify_all(s.model, s.known)) {
    const Classification original = c;
    at_default += c.unknown;
    ASSERT_TRUE(set_known_acceptance(s.model, c, 0.5).ok());
    at_half += c.unknown;
    EXPECT_EQ(c.winner, original.winner);
    EXPECT_EQ(c.scores, original.scores);
    EXPECT_EQ(c.novelty, original.novelty);
    ASSERT_TRUE(set_known_acceptance(s.model, c, 1.0).ok());
    at_all += c.unknown;
    ASSERT_TRUE(set_known_acceptance(s.model, c, 0).ok());  // back to the model's default
    EXPECT_EQ(c.unknown, original.unknown);
    EXPECT_EQ(c.unknown_reason, original.unknown_reason);
  }
  EXPECT_GE(at_half, at_default);
  EXPECT_LE(at_all, at_default);
  EXPECT_GT(at_half, at_all);  // accepting half the known clouds rejects some of 20
  Classification c = classify_all(s.model, {s.known.front()}).front();
  for (double bad : {-0.1, 1.5, std::nan("")}) {
    auto st = set_known_acceptance(s.model, c, bad);
    ASSERT_FALSE(st.ok()) << bad;
    EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(st.error().message.find("known acceptance"), std::string::npos);
  }
}

TEST(Novelty, OnlyTheCalibratedMethodHasOne) {
  const OpenSet& s = open_set();
  auto c = classify(s.model, s.known.front().cloud, MethodId::kUSH);
  ASSERT_TRUE(c.ok());
  EXPECT_TRUE(std::isnan(c->novelty));
  EXPECT_FALSE(c->unknown);
}

// A flat patch has no keypoint: Bag of Keypoints has an empty histogram and cannot judge it.
TEST(Novelty, AKeypointMethodWithNoKeypointCannotJudge) {
  const OpenSet& s = open_set();
  Cloud plane;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) plane.points.emplace_back(0.005f * float(i), 0.005f * float(j), 0.f);
  auto c = classify(s.model, plane, MethodId::kBoK);
  ASSERT_TRUE(c.ok()) << c.error().message;
  ASSERT_EQ(c->keypoints, 0u);
  EXPECT_TRUE(c->unknown);
  EXPECT_TRUE(std::isnan(c->novelty));
  EXPECT_NE(c->unknown_reason.find("bok cannot judge"), std::string::npos) << c->unknown_reason;
  EXPECT_GE(c->winner, 0);
  ASSERT_TRUE(set_known_acceptance(s.model, *c, 1.0).ok());  // no operating point makes it judge
  EXPECT_TRUE(c->unknown);
  // Seen from above and from below (two views, decided apart): neither can be judged, nor can the scan.
  std::vector<std::optional<Vec3>> sensors(plane.points.size(), Vec3(0.15f, 0.15f, 2.f));
  for (size_t i = 0; i < sensors.size(); i += 2) sensors[i] = Vec3(0.15f, 0.15f, -2.f);
  auto both = classify_fused(s.model, plane, sensors, MethodId::kBoK);
  ASSERT_TRUE(both.ok()) << both.error().message;
  EXPECT_TRUE(both->unknown);
  EXPECT_TRUE(std::isnan(both->novelty));
  EXPECT_NE(both->unknown_reason.find("bok cannot judge"), std::string::npos) << both->unknown_reason;
}

TEST(Novelty, TrainingRejectsAnImpossibleKnownAcceptanceOrPrefix) {
  TrainParams accepting_nothing = open_set_params(), past_the_top = open_set_params();
  accepting_nothing.known_acceptance = 0;
  past_the_top.novelty_prefix = 1.5;
  for (const auto& [p, name] : {std::pair{accepting_nothing, "known_acceptance"}, std::pair{past_the_top, "novelty_prefix"}}) {
    auto m = train(without(test::synthetic_views(2, 2, 1), "can"), p);
    ASSERT_FALSE(m.ok()) << name;
    EXPECT_EQ(m.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(m.error().message.find(name), std::string::npos) << m.error().message;
  }
}

// A cloud's novelty joins that of its top-down prefix (TrainParams::novelty_prefix). A model of format 9
// or older, or without the "novelty_prefix" parameter, judges the cloud alone. The decision is
// the same either way, and so is the novelty of a cloud whose prefix would keep too few points.
TEST(Novelty, JoinsThatOfTheCloudsTopDownPrefix) {
  const OpenSet& s = open_set();
  auto before = deserialize(test::as_format_9(test::format_11_bytes(s.model)));
  auto unnamed = deserialize(test::without_parameter(serialize(s.model), "novelty_prefix"));
  ASSERT_TRUE(before.ok() && unnamed.ok()) << before.error().message;
  std::vector<TrainingCloud> clouds = s.known;
  clouds.insert(clouds.end(), s.unknown.begin(), s.unknown.end());
  size_t with_prefix = 0;
  for (const TrainingCloud& t : clouds) {
    auto a = classify(s.model, t.cloud), b = classify(*before, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->scores, b->scores);
    // The points classified (after the scan filters) decide whether the prefix keeps 300.
    const bool prefix = std::lround(0.55 * double(a->points)) >= 300;
    with_prefix += prefix;
    EXPECT_EQ(std::abs(a->novelty - b->novelty) > 1e-9 * b->novelty, prefix) << a->points << " points";
    auto u = classify(*unnamed, t.cloud);
    ASSERT_TRUE(u.ok());
    EXPECT_EQ(u->novelty, b->novelty);
    // Too small for a prefix: every 4th of the first 1000 points of the view (250, a prefix of 138).
    Cloud few{{}, t.cloud.sensor, {}};
    for (size_t i = 0; i < 1000 && i < t.cloud.points.size(); i += 4) few.points.push_back(t.cloud.points[i]);
    auto c = classify(s.model, few), d = classify(*before, few);
    ASSERT_TRUE(c.ok() && d.ok());
    EXPECT_EQ(c->novelty, d->novelty);
  }
  EXPECT_GE(with_prefix, clouds.size() - 2);  // measured 28 of 30
}

TEST(Novelty, SurvivesSerialisation) {
  const OpenSet& s = open_set();
  auto back = deserialize(serialize(s.model));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(calibration(*back).novelty_scale, calibration(s.model).novelty_scale);
  EXPECT_EQ(calibration(*back).novelty_quantiles, calibration(s.model).novelty_quantiles);
  EXPECT_EQ(calibration(*back).novelty_threshold, calibration(s.model).novelty_threshold);
  EXPECT_EQ(calibration(*back).novelty_objects, calibration(s.model).novelty_objects);
  EXPECT_EQ(calibration(*back).reference_object, calibration(s.model).reference_object);
  for (const TrainingCloud& t : s.unknown) {
    auto a = classify(s.model, t.cloud), b = classify(*back, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->novelty, b->novelty);
    EXPECT_EQ(a->unknown, b->unknown);
  }
}

// An augmented cloud (a simulated sensor's view, the zoo's objects added to real ones) widens what the
// decision learns, never what the model calls known: novelty measures a cloud against the same training
// on the other clouds alone. Here the cans' views are learnt as boxes: marked augmented, they change no
// score of the decision, but a new can is measured against the real boxes.
TEST(Novelty, AugmentedCloudsAreLearntButNotMeasuredAgainst) {
  std::vector<TrainingCloud> plain = without(test::synthetic_views(6, 3, 1), "can"), marked = plain;
  for (TrainingCloud c : test::synthetic_views(6, 3, 1))
    if (c.category == "can") {
      c.category = "box";
      plain.push_back(c);
      c.augmented = true;
      marked.push_back(c);
    }
  auto a = train(marked, open_set_params()), b = train(plain, open_set_params());
  ASSERT_TRUE(a.ok() && b.ok());
  // Novelty is calibrated as the model of the clouds not augmented calibrates it (open_set()'s).
  EXPECT_EQ(novelty_calibration(*a).novelty_quantiles, calibration(open_set().model).novelty_quantiles);
  EXPECT_EQ(novelty_calibration(*a).novelty_scale, calibration(open_set().model).novelty_scale);
  EXPECT_EQ(&novelty_calibration(*b), &calibration(*b));  // nothing augmented: the model's own
  double ratio = 0;
  size_t cans = 0;
  for (const TrainingCloud& t : test::synthetic_views(5, 2, 2)) {
    if (t.category != "can") continue;
    auto x = classify(*a, t.cloud), y = classify(*b, t.cloud);
    ASSERT_TRUE(x.ok() && y.ok());
    EXPECT_EQ(x->scores, y->scores);  // the decision learnt them alike
    EXPECT_GT(x->novelty, y->novelty);
    ratio += x->novelty / y->novelty, ++cans;
  }
  ASSERT_EQ(cans, 10u);
  std::cout << "cans learnt as boxes: novelty " << ratio / double(cans) << " x as high marked augmented\n";
  // Measured 1.92 (2.26 without the top-down prefix's novelty, 2.96 with the larger evidence, not the
  // sum).
  EXPECT_GE(ratio / double(cans), 1.85);
  // The novelty model survives serialisation, and so does every novelty.
  const std::vector<uint8_t> bytes = serialize(*a);
  auto back = deserialize(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(novelty_calibration(*back).novelty_quantiles, novelty_calibration(*a).novelty_quantiles);
  for (const TrainingCloud& t : open_set().unknown) {
    auto x = classify(*a, t.cloud), y = classify(*back, t.cloud);
    ASSERT_TRUE(x.ok() && y.ok());
    EXPECT_EQ(x->novelty, y->novelty);
    EXPECT_EQ(x->unknown, y->unknown);
  }
  // Declared format 7 (no novelty model), the novelty model's bytes are left over: damage, not a model
  // read without them.
  auto seven = test::read_as_format(test::format_11_bytes(*a), 7);
  ASSERT_FALSE(seven.ok());
  EXPECT_NE(seven.error().message.find("unexpected trailing bytes"), std::string::npos) << seven.error().message;
}

// With a novelty model, the model's own calibration measures no novelty (the novelty model's is what is
// read); where the novelty model cannot calibrate (a category only augmented clouds have), the model
// measures its own. Either way the margin and the head's share are those of the same model measuring
// novelty, and so are its scores. measure_novelty false: no novelty at all, nothing unknown.
TEST(Novelty, TheModelMeasuresItsOwnNoveltyOnlyWhereNoNoveltyModelDoes) {
  const std::vector<TrainingCloud> data = test::synthetic_views(6, 3, 1);
  std::vector<TrainingCloud> half = data, cans = data;
  for (size_t i = 0; i < data.size(); ++i) {
    half[i].augmented = i % 2 == 1;              // every category keeps clouds not augmented
    cans[i].augmented = data[i].category == "can";  // no can the novelty model could learn
  }
  TrainParams blind = open_set_params();
  blind.measure_novelty = false;
  auto own = train(data, open_set_params()), apart = train(half, open_set_params()), fallback = train(cans, open_set_params()),
       none = train(data, blind);
  ASSERT_TRUE(own.ok() && apart.ok() && fallback.ok() && none.ok());
  ASSERT_FALSE(calibration(*own).novelty_scale.empty());
  EXPECT_NE(&novelty_calibration(*apart), &calibration(*apart));
  EXPECT_TRUE(calibration(*apart).novelty_scale.empty());
  EXPECT_FALSE(novelty_calibration(*apart).novelty_scale.empty());
  EXPECT_EQ(&novelty_calibration(*fallback), &calibration(*fallback));
  EXPECT_EQ(calibration(*fallback).novelty_quantiles, calibration(*own).novelty_quantiles);  // the same clouds learnt
  EXPECT_TRUE(calibration(*none).novelty_scale.empty());
  for (const Model* m : {&*apart, &*fallback, &*none}) {
    EXPECT_EQ(calibration(*m).settle_margin, calibration(*own).settle_margin);
    EXPECT_EQ(calibration(*m).held_out_accuracy, calibration(*own).held_out_accuracy);
    EXPECT_EQ(calibration(*m).fusion_head_share, calibration(*own).fusion_head_share);
  }
  for (const TrainingCloud& t : test::synthetic_views(3, 2, 2)) {
    auto a = classify(*own, t.cloud), b = classify(*fallback, t.cloud), c = classify(*none, t.cloud);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok());
    EXPECT_EQ(b->scores, a->scores);
    EXPECT_EQ(b->novelty, a->novelty);
    EXPECT_EQ(c->scores, a->scores);
    EXPECT_TRUE(std::isnan(c->novelty));
    EXPECT_FALSE(c->unknown);
  }
}

}  // namespace
}  // namespace glimpse
