// The decision track on its own (a pure function of the score history): it counts category changes,
// settles on a stable margin, treats "unknown" as one more category with its own, longer window, and
// damps an outlier.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "glimpse/learning/probabilities.h"
#include "glimpse/session/session.h"

namespace glimpse {
namespace {

// A scripted track over scores alone (no novelty): smoothing, stability window, full margin and settling
// confidence given, the other parameters the test's; each step folds one chunk's scores.
struct ScoreTrack {
  SessionParams p;
  DecisionTrack t;
  bool keypoints_matter = false;
  ScoreTrack(double smoothing, int window, double full_margin, double settle_confidence) {
    p.smoothing = smoothing;
    p.stability_window = window;
    p.full_margin = full_margin;
    p.settle_confidence = settle_confidence;
  }
  StreamDecision step(const std::vector<double>& scores, size_t keypoints = 0) {
    track_decision(t, scores, keypoints, keypoints_matter, p);
    return t.decision;
  }
};

// With the model's temperature, a category's confidence is the winner's calibrated probability times
// the share of the window it won, and it settles at settle_probability.
TEST(DecisionTrack, AModelWithProbabilitiesSettlesOnTheWinnersProbability) {
  ScoreTrack track(1.0, 2, 0.4, 0.5);
  track.p.probability_temperature = 0.25;
  track.p.settle_probability = 0.9;
  StreamDecision d = track.step({0.5, 0.3, 0.2});
  const double p_first = temperature_probabilities(std::vector<double>{0.5, 0.3, 0.2}, 0.25)[0];  // 0.82
  EXPECT_NEAR(d.confidence, p_first * 0.5, 1e-12);  // held 1 of 2
  d = track.step({0.5, 0.3, 0.2});
  EXPECT_NEAR(d.confidence, p_first, 1e-12);
  EXPECT_FALSE(d.settled) << "0.82 < 0.9, though the margin rule (0.2 of 0.4) would settle";
  d = track.step({0.6, 0.2, 0.2});
  EXPECT_GT(d.confidence, 0.9);  // 0.6^4 / (0.6^4 + 2 x 0.2^4) = 0.976
  EXPECT_TRUE(d.settled);
  d = track.step({0.5, 0.3, 0.2});
  EXPECT_TRUE(d.settled) << "0.82 stays within unsettle_margin of 0.9";
  track.p.probability_temperature = 0;  // no probabilities: the margin rule
  d = track.step({0.5, 0.3, 0.2});
  EXPECT_NEAR(d.confidence, 0.5, 1e-12);
}

TEST(DecisionTrack, CountsChangesAndSettlesOnAStableMargin) {
  ScoreTrack track(1.0, 3, 0.4, 0.6);  // no smoothing: the script reads directly
  track.keypoints_matter = true;
  track.p.min_keypoints = 5;
  auto step = [&](std::vector<double> s, size_t kp = 20) { return track.step(s, kp); };
  StreamDecision d = step({0.5, 0.3, 0.2});
  EXPECT_EQ(d.winner, 0);
  EXPECT_EQ(d.category_changes, 0);
  EXPECT_EQ(d.winner_held_chunks, 1);
  EXPECT_FALSE(d.settled);  // margin 0.2 of 0.4, held 1 of 3
  d = step({0.2, 0.6, 0.2});
  EXPECT_EQ(d.winner, 1);
  EXPECT_EQ(d.category_changes, 1);
  EXPECT_EQ(d.winner_held_chunks, 1);
  d = step({0.1, 0.8, 0.1});
  d = step({0.1, 0.8, 0.1});
  EXPECT_EQ(d.category_changes, 1);
  EXPECT_EQ(d.winner_held_chunks, 3);
  EXPECT_NEAR(d.confidence, 1.0, 1e-12);  // margin 0.7 >= 0.4, held 3 of 3
  EXPECT_TRUE(d.settled);
  d = step({0.1, 0.8, 0.1}, 3);
  EXPECT_FALSE(d.settled) << "too few keypoints to settle";
  d = step({0.45, 0.4, 0.15});
  EXPECT_EQ(d.winner, 0);
  EXPECT_EQ(d.category_changes, 2);
  EXPECT_FALSE(d.settled) << "a change resets the stability";
  EXPECT_NEAR(d.confidence, (0.05 / 0.4) * (1.0 / 3.0), 1e-9);
}

TEST(DecisionTrack, ASettledWinnerStaysSettledThroughASmallDip) {
  ScoreTrack track(1.0, 2, 0.4, 0.6);
  track.p.unsettle_margin = 0.2;
  auto step = [&](std::vector<double> s) { return track.step(s); };
  EXPECT_FALSE(step({0.4, 0.6}).settled);                         // 0.5 x held 1 of 2
  EXPECT_FALSE(step({0.9, 0.1}).settled);                         // a change: 1.0 x held 1 of 2
  EXPECT_TRUE(step({0.9, 0.1}).settled);                          // 1.0
  StreamDecision d = step({0.7, 0.3});                                  // 0.4 / 0.4 = 1.0
  EXPECT_TRUE(d.settled);
  d = step({0.6, 0.4});                                           // 0.5: below 0.6, above 0.6 - 0.2
  EXPECT_NEAR(d.confidence, 0.5, 1e-12);
  EXPECT_TRUE(d.settled) << "a small dip keeps a settled decision";
  d = step({0.55, 0.45});                                         // 0.25: below 0.4
  EXPECT_FALSE(d.settled) << "a collapse of the margin unsettles";
  EXPECT_FALSE(step({0.6, 0.4}).settled) << "once unsettled, it must reach 0.6 again";
  EXPECT_TRUE(step({0.75, 0.25}).settled);
  // A new winner is never settled on the strength of the old one's history.
  track.p.unsettle_margin = 1.0;
  EXPECT_FALSE(step({0.2, 0.8}).settled);
}

// A decision track over two categories with a novelty threshold of 2: a window of 2 chunks, a full margin
// of 0.4, settling at confidence 0.6, "unknown" fully confident at 1.5 x the threshold; "unknown" and
// the categories settle alike (no longer window, no novelty share) unless a test says otherwise.
struct NoveltyTrack {
  SessionParams p;
  DecisionTrack t;
  static constexpr double kThreshold = 2.0;
  explicit NoveltyTrack(double smoothing) {
    p.smoothing = smoothing;
    p.stability_window = 2;
    p.full_margin = 0.4;
    p.settle_confidence = 0.6;
    p.unknown_full_excess = 0.5;
    p.unknown_settle_window = 2;
    p.unknown_settle_confidence = 0.6;
    p.settle_novelty_share = 1.0;
  }
  StreamDecision step(std::vector<double> scores, std::vector<double> novelty, std::string cannot = {}) {
    ChunkEvidence e;
    e.scores = std::move(scores);
    e.novelty = std::move(novelty);
    e.keypoints = 20;
    e.cannot_judge = std::move(cannot);
    track_decision(t, e, false, kThreshold, p);
    return t.decision;
  }
};

// "Unknown" is one more category: it changes, holds and settles like one; the winner stays the nearest.
TEST(DecisionTrack, UnknownSettlesLikeACategory) {
  NoveltyTrack track(1.0);
  const SessionParams& p = track.p;
  auto step = [&](std::vector<double> s, std::vector<double> novelty, std::string cannot = {}) {
    return track.step(std::move(s), std::move(novelty), std::move(cannot));
  };
  StreamDecision d = step({0.9, 0.1}, {1.0, 3.0});
  EXPECT_FALSE(d.unknown);
  EXPECT_DOUBLE_EQ(d.novelty, 1.0);  // the winner's
  d = step({0.9, 0.1}, {1.0, 3.0});
  EXPECT_TRUE(d.settled);
  d = step({0.9, 0.1}, {2.5, 3.0});  // novelty 2.5 above 2: unknown, closest still category 0
  EXPECT_TRUE(d.unknown);
  EXPECT_EQ(d.winner, 0);
  EXPECT_EQ(d.category_changes, 1);
  EXPECT_EQ(d.winner_held_chunks, 1);
  EXPECT_FALSE(d.settled) << "a change resets the stability";
  EXPECT_NE(d.unknown_reason.find("novelty 2.50 above 2.00"), std::string::npos) << d.unknown_reason;
  EXPECT_NEAR(d.confidence, 0.5 * 0.5, 1e-12);  // (2.5 / 2 - 1) / 0.5 = 0.5, held 1 of 2
  d = step({0.9, 0.1}, {3.0, 3.0});
  EXPECT_EQ(d.category_changes, 1);
  EXPECT_EQ(d.winner_held_chunks, 2);
  EXPECT_NEAR(d.confidence, 1.0, 1e-12);  // (3 / 2 - 1) / 0.5 = 1, held 2 of 2
  EXPECT_TRUE(d.settled) << "unknown settles like a category";
  d = step({0.9, 0.1}, {1.5, 3.0});
  EXPECT_FALSE(d.unknown);
  EXPECT_EQ(d.category_changes, 2);
  EXPECT_FALSE(d.settled);
  d = step({0.9, 0.1}, {1.5, 3.0}, "0 keypoints: bok cannot judge this cloud (an empty histogram)");
  EXPECT_TRUE(d.unknown);
  EXPECT_TRUE(std::isnan(d.novelty));
  EXPECT_EQ(d.unknown_reason.rfind("0 keypoints", 0), 0u);
  EXPECT_EQ(d.confidence, 0.0);  // cannot judge is never a settled answer
  // Without a threshold (an uncalibrated method) nothing is unknown by novelty.
  DecisionTrack plain;
  ChunkEvidence e;
  e.scores = {0.9, 0.1};
  e.novelty = {100.0, 100.0};
  track_decision(plain, e, false, std::nan(""), p);
  EXPECT_FALSE(plain.decision.unknown);
}

// "Unknown" settles only when the newest chunk's own novelty agrees, as a category needs the newest
// chunk's own scores to: a smoothed novelty the scan has left behind is not a settled "none of these".
TEST(DecisionTrack, UnknownSettlesOnlyWhenTheNewestChunkIsNovelToo) {
  NoveltyTrack track(0.5);
  auto step = [&](std::vector<double> novelty) { return track.step({0.9, 0.1}, std::move(novelty)); };
  StreamDecision d = step({6.0, 6.0});  // smoothed 6: unknown, held 1 of 2
  EXPECT_TRUE(d.unknown);
  EXPECT_FALSE(d.settled);
  d = step({1.0, 6.0});  // smoothed 0.5 * 1 + 0.5 * 6 = 3.5: still unknown, held 2 of 2, confidence 1
  EXPECT_TRUE(d.unknown);
  EXPECT_DOUBLE_EQ(d.novelty, 3.5);
  EXPECT_NEAR(d.confidence, 1.0, 1e-12);  // (3.5 / 2 - 1) / 0.5 = 1.5, clamped
  EXPECT_FALSE(d.settled) << "the newest chunk (novelty 1) looks like category 0";
  d = step({6.0, 6.0});  // smoothed 4.75, the newest chunk novel too
  EXPECT_TRUE(d.unknown);
  EXPECT_TRUE(d.settled);
}

// Cautious both ways: "unknown" settles after its own longer window at its own confidence, and a
// category only while its novelty is well inside the threshold.
TEST(DecisionTrack, UnknownNeedsItsLongerWindowAndACategoryANoveltyWellInside) {
  NoveltyTrack track(1.0);
  track.p.unknown_settle_window = 3;
  track.p.unknown_settle_confidence = 1.0;
  track.p.settle_novelty_share = 0.8;  // a category settles at novelty <= 1.6
  auto step = [&](double novelty) { return track.step({0.9, 0.1}, {novelty, 3.0}); };
  StreamDecision d = step(1.8);
  EXPECT_FALSE(d.unknown);
  d = step(1.8);
  EXPECT_NEAR(d.confidence, 1.0, 1e-12);
  EXPECT_FALSE(d.settled) << "novelty 1.8: known, but not well inside the threshold 2";
  d = step(1.5);
  EXPECT_TRUE(d.settled) << "novelty 1.5 <= 0.8 x 2";
  d = step(1.8);
  EXPECT_TRUE(d.settled) << "the share gates settling, not staying settled";
  // Unknown at confidence 0.5 (novelty 2.5) never settles at 1.0, however long it holds.
  for (int i = 0; i < 5; ++i) {
    d = step(2.5);
    EXPECT_TRUE(d.unknown);
    EXPECT_FALSE(d.settled) << i;
  }
  // At novelty 3 (confidence 1), it needs each of the last 3 decisions unknown at that confidence...
  d = step(1.0);
  EXPECT_FALSE(d.unknown);
  d = step(3.0);
  d = step(3.0);
  EXPECT_NEAR(d.confidence, 1.0, 1e-12);
  EXPECT_FALSE(d.settled) << "held 2 of the 3 chunks unknown needs";
  d = step(3.0);
  EXPECT_TRUE(d.settled);
  // ... and stays settled within unsettle_margin of its own confidence.
  d = step(2.9);  // (2.9 / 2 - 1) / 0.5 = 0.9 >= 1.0 - 0.2
  EXPECT_TRUE(d.settled);
  d = step(2.5);  // 0.5 < 0.8
  EXPECT_FALSE(d.settled);
}

TEST(DecisionTrack, SettlingNeedsTheWholeWindowAndTheNewestChunkToAgree) {
  ScoreTrack track(0.5, 4, 0.1, 0.5);
  auto step = [&](std::vector<double> s) { return track.step(s); };
  EXPECT_FALSE(step({0.9, 0.1}).settled);
  StreamDecision d = step({0.9, 0.1});
  EXPECT_NEAR(d.confidence, 0.5, 1e-12);  // full margin x held 2 of 4: confident enough, not steady enough
  EXPECT_FALSE(d.settled);
  EXPECT_FALSE(step({0.9, 0.1}).settled);
  d = step({0.4, 0.6});  // the newest chunk alone prefers 1; the smoothed winner is still 0
  EXPECT_EQ(d.winner, 0);
  EXPECT_GE(d.confidence, 0.5);
  EXPECT_FALSE(d.settled) << "the newest chunk disagrees";
  EXPECT_TRUE(step({0.9, 0.1}).settled);
}

TEST(DecisionTrack, SmoothingDampsASingleOutlier) {
  SessionParams p;
  p.smoothing = 0.3;
  DecisionTrack t;
  for (int i = 0; i < 5; ++i) track_decision(t, {0.7, 0.3}, 20, false, p);
  track_decision(t, {0.2, 0.8}, 20, false, p);
  EXPECT_EQ(t.decision.winner, 0);
  EXPECT_EQ(t.decision.category_changes, 0);
}

}  // namespace
}  // namespace glimpse
