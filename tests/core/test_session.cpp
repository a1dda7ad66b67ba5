// ScanSession: streaming a view chunk by chunk ends where classifying the whole view does; duplicates
// and empty chunks change nothing; the decision track counts changes and settles as specified.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "glimpse/session.h"
#include "glimpse/train_params.h"
#include "glimpse/views.h"
#include "synthetic.h"

namespace glimpse {
namespace {

std::shared_ptr<const Model> trained_model(float support_radius_m) {
  TrainParams p;
  p.bok_clusters = 12;
  p.bog_keypoint_clusters = 3;
  p.bog_volume_clusters = 2;
  p.kgh_clusters = 3;
  p.kgh_distance_bins = 4;
  p.decision.neighbours = 3;
  p.features.surface.support_radius_m = support_radius_m;
  auto m = train(test::synthetic_views(5, 2, 11), p);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return m.ok() ? std::make_shared<const Model>(std::move(*m)) : nullptr;
}

const std::shared_ptr<const Model>& fixed_radius_model() {
  static const auto m = trained_model(0.025f);
  return m;
}

std::vector<Cloud> chunks_of(const Cloud& view, size_t n, bool random, uint64_t seed) {
  std::vector<uint32_t> order;
  if (random) {
    order.resize(view.points.size());
    std::iota(order.begin(), order.end(), 0u);
    std::mt19937_64 rng(seed);
    for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  } else {
    order = top_down_order(view.points);
  }
  std::vector<Cloud> out(n);
  for (size_t i = 0; i < order.size(); ++i) {
    Cloud& c = out[i * n / order.size()];
    c.sensor = view.sensor;
    c.points.push_back(view.points[order[i]]);
  }
  return out;
}

Decision stream(const std::shared_ptr<const Model>& model, const std::vector<Cloud>& chunks, Method method) {
  SessionParams sp;
  sp.method = method;
  sp.min_points_for_radius = 1;  // the model fixes r: start at once
  auto session = ScanSession::create(model, sp);
  EXPECT_TRUE(session.ok());
  Decision d;
  for (const Cloud& c : chunks) {
    auto r = (*session)->add(c);
    EXPECT_TRUE(r.ok()) << r.error().message;
    if (r.ok()) d = *r;
  }
  return d;
}

TEST(ScanSession, StreamingEndsLikeTheWholeView) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  for (uint64_t seed : {21u, 22u}) {
    const auto views = test::synthetic_views(1, 1, seed);
    for (const LabelledCloud& view : views) {
      auto whole = classify(*model, view.cloud, Method::kBoK);
      ASSERT_TRUE(whole.ok()) << whole.error().message;
      for (size_t n : {1u, 4u, 12u}) {
        for (bool random : {false, true}) {
          const Decision d = stream(model, chunks_of(view.cloud, n, random, seed), Method::kBoK);
          SCOPED_TRACE(view.category + " in " + std::to_string(n) + (random ? " random" : " top-down") + " chunks");
          EXPECT_EQ(d.points, whole->points);
          // Same keypoints up to float summation order in the neighbourhood fits (tolerance: 1 in 20).
          EXPECT_NEAR(static_cast<double>(d.keypoints), static_cast<double>(whole->keypoints),
                      std::max(1.0, 0.05 * static_cast<double>(whole->keypoints)));
          if (n == 1) {
            EXPECT_EQ(d.winner, whole->winner);
          }
        }
      }
    }
  }
}

TEST(ScanSession, FinalDecisionAgreesWithClassifyOnMostViews) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  int agree = 0, total = 0;
  for (const LabelledCloud& view : test::synthetic_views(2, 1, 31)) {
    auto whole = classify(*model, view.cloud, Method::kFusion);
    ASSERT_TRUE(whole.ok());
    const Decision d = stream(model, chunks_of(view.cloud, 8, false, 1), Method::kFusion);
    agree += d.winner == whole->winner;
    ++total;
  }
  // Streamed scores are smoothed over the history and VFH/ESF lag up to 10 % of the points.
  EXPECT_GE(agree, total - 1);
}

TEST(ScanSession, DuplicateOverlappingAndEmptyChunksChangeNothing) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  const LabelledCloud view = test::synthetic_views(1, 1, 41)[1];
  const auto chunks = chunks_of(view.cloud, 6, false, 0);
  SessionParams sp;
  sp.method = Method::kBoK;
  auto session = *ScanSession::create(model, sp);
  Decision d;
  for (const Cloud& c : chunks) d = *session->add(c);
  const size_t points = d.points, keypoints = d.keypoints;
  ASSERT_GT(points, 0u);
  auto again = session->add(chunks[2]);  // a re-sent chunk
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->points, points);
  EXPECT_EQ(again->keypoints, keypoints);
  Cloud overlap = chunks[3];
  overlap.points.insert(overlap.points.end(), chunks[4].points.begin(), chunks[4].points.end());
  auto over = session->add(overlap);
  ASSERT_TRUE(over.ok());
  EXPECT_EQ(over->points, points);
  auto empty = session->add(Cloud{});
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->points, points);
  EXPECT_EQ(empty->winner, d.winner);
  EXPECT_EQ(empty->chunk_index, chunks.size() + 2);
}

TEST(ScanSession, NothingToDecideBeforeEnoughPoints) {
  auto model = fixed_radius_model();
  ASSERT_TRUE(model);
  SessionParams sp;
  sp.min_points_for_radius = 300;
  auto session = *ScanSession::create(model, sp);
  const LabelledCloud view = test::synthetic_views(1, 1, 51)[0];
  auto first = session->add(Cloud{{view.cloud.points.begin(), view.cloud.points.begin() + 50}, view.cloud.sensor});
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->winner, -1);
  EXPECT_EQ(first->points, 50u);
  EXPECT_FALSE(first->settled);
}

TEST(ScanSession, LimitsAndBadInput) {
  auto model = fixed_radius_model();
  ASSERT_TRUE(model);
  EXPECT_FALSE(ScanSession::create(nullptr).ok());
  EXPECT_EQ(ScanSession::create(std::make_shared<const Model>()).error().code, ErrorCode::kFailedPrecondition);

  SessionParams sp;
  sp.max_chunks = 2;
  sp.max_chunk_points = 100;
  sp.max_points = 150;
  auto session = *ScanSession::create(model, sp);
  Cloud nan{{Vec3(0, 0, 0), Vec3(NAN, 0, 0)}, std::nullopt};
  auto bad = session->add(nan);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("point 1"), std::string::npos);

  const LabelledCloud view = test::synthetic_views(1, 1, 61)[0];
  Cloud big{{view.cloud.points.begin(), view.cloud.points.begin() + 101}, std::nullopt};
  EXPECT_EQ(session->add(big).error().code, ErrorCode::kResourceExhausted);
  Cloud ok{{view.cloud.points.begin(), view.cloud.points.begin() + 100}, view.cloud.sensor};
  ASSERT_TRUE(session->add(ok).ok());
  Cloud more{{view.cloud.points.begin() + 100, view.cloud.points.begin() + 200}, view.cloud.sensor};
  auto capped = session->add(more);
  ASSERT_TRUE(capped.ok());
  EXPECT_LE(capped->points, 150u) << "points beyond the limit are not kept";
  auto full = session->add(Cloud{});
  ASSERT_FALSE(full.ok());
  EXPECT_EQ(full.error().code, ErrorCode::kResourceExhausted);
  EXPECT_NE(full.error().message.find("limit"), std::string::npos);

  SessionParams few;
  few.max_chunks = 2;
  auto short_session = *ScanSession::create(model, few);
  ASSERT_TRUE(short_session->add(Cloud{}).ok());
  ASSERT_TRUE(short_session->add(Cloud{}).ok());
  auto third = short_session->add(Cloud{});
  ASSERT_FALSE(third.ok());
  EXPECT_EQ(third.error().code, ErrorCode::kResourceExhausted);
  EXPECT_NE(third.error().message.find("chunks"), std::string::npos);
}

TEST(DecisionTrack, CountsChangesAndSettlesOnAStableMargin) {
  SessionParams p;
  p.smoothing = 1.0;  // no smoothing: the script reads directly
  p.stability_window = 3;
  p.full_margin = 0.4;
  p.settle_confidence = 0.6;
  p.min_keypoints = 5;
  DecisionTrack t;
  auto step = [&](std::vector<double> s, size_t kp = 20) {
    track_decision(t, s, kp, true, p);
    return t.decision;
  };
  Decision d = step({0.5, 0.3, 0.2});
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
  SessionParams p;
  p.smoothing = 1.0;
  p.stability_window = 2;
  p.full_margin = 0.4;
  p.settle_confidence = 0.6;
  p.unsettle_margin = 0.2;
  DecisionTrack t;
  auto step = [&](std::vector<double> s) {
    track_decision(t, s, 0, false, p);
    return t.decision;
  };
  EXPECT_FALSE(step({0.4, 0.6}).settled);                         // 0.5 x held 1 of 2
  EXPECT_FALSE(step({0.9, 0.1}).settled);                         // a change: 1.0 x held 1 of 2
  EXPECT_TRUE(step({0.9, 0.1}).settled);                          // 1.0
  Decision d = step({0.7, 0.3});                                  // 0.4 / 0.4 = 1.0
  EXPECT_TRUE(d.settled);
  d = step({0.6, 0.4});                                           // 0.5: below 0.6, above 0.6 - 0.2
  EXPECT_NEAR(d.confidence, 0.5, 1e-12);
  EXPECT_TRUE(d.settled) << "a small dip keeps a settled decision";
  d = step({0.55, 0.45});                                         // 0.25: below 0.4
  EXPECT_FALSE(d.settled) << "a collapse of the margin unsettles";
  EXPECT_FALSE(step({0.6, 0.4}).settled) << "once unsettled, it must reach 0.6 again";
  EXPECT_TRUE(step({0.75, 0.25}).settled);
  // A new winner is never settled on the strength of the old one's history.
  p.unsettle_margin = 1.0;
  EXPECT_FALSE(step({0.2, 0.8}).settled);
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
