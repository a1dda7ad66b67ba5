// ScanSession: streaming a view chunk by chunk ends where classifying the whole view does; duplicates
// and empty chunks change nothing; limits and bad input are refused (the decision track on its own:
// test_session_track.cpp; the scan's features: test_scan_features.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "glimpse/session/session.h"
#include "glimpse/learning/train_params.h"
#include "chunks.h"
#include "shapes.h"
#include "synthetic.h"
#include "trained_model.h"

namespace glimpse {
namespace {

std::shared_ptr<const Model> trained_model(float support_radius_m) {
  TrainParams p = test::small_params();
  p.features.surface.support_radius_m = support_radius_m;
  auto m = train(test::synthetic_views(5, 2, 11), p);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return m.ok() ? std::make_shared<const Model>(std::move(*m)) : nullptr;
}

const std::shared_ptr<const Model>& fixed_radius_model() {
  static const auto m = trained_model(0.025f);
  return m;
}

const std::shared_ptr<const Model>& automatic_radius_model() {
  static const auto m = trained_model(0);
  return m;
}

using test::chunks_of;
using test::concatenated;
using test::Order;

StreamDecision stream(const std::shared_ptr<const Model>& model, const std::vector<Cloud>& chunks, MethodId method,
                bool finish = false) {
  SessionParams sp;
  sp.method = method;
  auto session = ScanSession::create(model, sp);
  EXPECT_TRUE(session.ok());
  StreamDecision d;
  for (const Cloud& c : chunks) {
    auto r = (*session)->add(c);
    EXPECT_TRUE(r.ok()) << r.error().message;
    if (r.ok()) d = *r;
  }
  if (finish) {
    auto r = (*session)->finish();
    EXPECT_TRUE(r.ok());
    if (r.ok()) d = *r;
  }
  return d;
}

// And a finished stream's raw scores are Classify's of the accumulated cloud, for every method.
TEST(ScanSession, FinishedStreamScoresAreClassifysOfTheWholeCloud) {
  for (const auto* model : {&fixed_radius_model(), &automatic_radius_model()}) {
    ASSERT_TRUE(*model);
    for (const TrainingCloud& view : test::synthetic_views(1, 1, 81))
      for (bool sensor : {true, false})
        for (MethodId m : {MethodId::kBoK, MethodId::kUSH, MethodId::kVFH, MethodId::kESF, MethodId::kSize, MethodId::kFusion}) {
          SCOPED_TRACE(view.category + " " + method_name(m) + (sensor ? " with" : " without") + " a sensor");
          const std::vector<Cloud> chunks = chunks_of(view.cloud, 9, Order::kTopDown, 3, sensor);
          auto whole = classify(**model, concatenated(chunks), m);
          ASSERT_TRUE(whole.ok()) << whole.error().message;
          const StreamDecision d = stream(*model, chunks, m, true);
          EXPECT_TRUE(d.final);
          EXPECT_EQ(d.points, whole->points);
          EXPECT_EQ(d.keypoints, whole->keypoints);
          ASSERT_EQ(d.raw_scores.size(), whole->scores.size());
          for (size_t c = 0; c < d.raw_scores.size(); ++c) EXPECT_EQ(d.raw_scores[c], whole->scores[c]) << c;
          EXPECT_EQ(d.scores, d.raw_scores);  // the final answer is Classify's, not the running average
          EXPECT_EQ(d.winner, whole->winner);
          // "None of these" too: Classify's novelty and unknown (fusion is the calibrated method).
          EXPECT_EQ(d.unknown, whole->unknown);
          EXPECT_EQ(d.unknown_reason, whole->unknown_reason);
          if (std::isfinite(whole->novelty)) {
            EXPECT_EQ(d.novelty, whole->novelty);
          } else {
            EXPECT_TRUE(std::isnan(d.novelty));
          }
          EXPECT_EQ(std::isfinite(d.novelty), m == MethodId::kFusion);
        }
  }
}

// A depth camera writes its invalid pixels as copies of one point: a stray point copied 3000 times is
// still one stray point, streamed or classified whole (both clean the points before the scan filters),
// and the answer is that of the scan with the stray point once.
TEST(ScanSession, AStrayPointCopiedManyTimesIsOneStrayPointStreamedOrWhole) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  const TrainingCloud view = test::synthetic_views(1, 1, 81)[0];
  std::vector<Cloud> chunks = chunks_of(view.cloud, 6, Order::kTopDown, 3);
  const Vec3 stray = bounds(view.cloud.points).max + Vec3(0.3f, 0.3f, 0.3f);
  Cloud once = concatenated(chunks);
  once.points.push_back(stray);
  chunks.back().points.insert(chunks.back().points.end(), 3000, stray);
  ASSERT_GT(3000u, view.cloud.points.size());  // more copies than points: the spacing's median is 0
  auto whole = classify(*model, concatenated(chunks), MethodId::kFusion);
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  auto single = classify(*model, once, MethodId::kFusion);
  ASSERT_TRUE(single.ok()) << single.error().message;
  EXPECT_GE(whole->filters.outliers, 1u);  // not the copies' neighbour: the stray point is one point
  EXPECT_EQ(whole->filters.outliers, single->filters.outliers);
  EXPECT_EQ(whole->scores, single->scores);
  const StreamDecision d = stream(model, chunks, MethodId::kFusion, true);
  EXPECT_TRUE(d.final);
  EXPECT_EQ(d.points, whole->points);
  EXPECT_EQ(d.raw_scores, whole->scores);
  EXPECT_EQ(d.unknown, whole->unknown);
}

// A scan whose chunks were decided but whose whole cloud Classify refuses (a view beside a cluster 70 m
// away: the density filter's leaf follows the scan's extent and leaves too few points) ends in
// Classify's error, never in an answer that is not final.
TEST(ScanSession, AScanClassifyRefusesEndsInClassifysError) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  const Cloud view = test::synthetic_views(1, 1, 81)[0].cloud;
  Cloud near, far;
  near.sensor = far.sensor = view.sensor;
  near.points.assign(view.points.begin(), view.points.begin() + 100);
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) far.points.emplace_back(70.f + 0.01f * float(i), 0.01f * float(j), 0.f);
  auto whole = classify(*model, concatenated({near, far}), MethodId::kFusion);
  ASSERT_FALSE(whole.ok()) << "the scene no longer fails Classify: make another";
  SessionParams sp;
  sp.method = MethodId::kFusion;
  auto session = *ScanSession::create(model, sp);
  auto first = session->add(near);
  ASSERT_TRUE(first.ok()) << first.error().message;
  ASSERT_FALSE(session->last().raw_scores.empty());  // the first chunk was decided
  ASSERT_TRUE(session->add(far).ok());
  auto finished = session->finish();
  ASSERT_FALSE(finished.ok()) << "final " << finished->final;
  EXPECT_EQ(finished.error().code, whole.error().code);
  EXPECT_NE(finished.error().message.find(whole.error().message), std::string::npos) << finished.error().message;
}

// A model that does not filter scans (one whose writer knew no filters) ends a stream as Classify does
// too: a view in millimetres is unknown by its size, with Classify's reason.
TEST(ScanSession, AnUnfilteredModelsStreamEndsUnknownBySizeAsClassifySays) {
  TrainParams p;
  p.methods = {MethodId::kUSH, MethodId::kVFH, MethodId::kFusion};
  p.filter_scans = false;
  auto trained = train(test::synthetic_views(4, 2, 11), p);
  ASSERT_TRUE(trained.ok()) << trained.error().message;
  const auto model = std::make_shared<const Model>(std::move(*trained));
  Cloud mm = test::synthetic_views(1, 1, 83)[0].cloud;
  for (Vec3& q : mm.points) q *= 1000.f;
  if (mm.sensor) *mm.sensor *= 1000.f;
  const std::vector<Cloud> chunks = chunks_of(mm, 2, Order::kTopDown, 7);
  auto whole = classify(*model, concatenated(chunks));
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  ASSERT_TRUE(whole->unknown);
  const StreamDecision d = stream(model, chunks, MethodId::kFusion, true);
  EXPECT_TRUE(d.final);
  EXPECT_TRUE(d.unknown);
  EXPECT_EQ(d.unknown_reason, whole->unknown_reason);
  EXPECT_EQ(d.unknown_reason.find("size far outside what the model learnt"), 0u) << d.unknown_reason;
}

// A model of balls and boxes: a streamed can and a 2 m wavy sheet end unknown exactly when Classify says
// so, at the stream's own operating point; the sheet, like nothing learnt, is unknown and settles so.
TEST(ScanSession, AStreamOfSomethingNeverLearntEndsAsClassifySaysAtItsOperatingPoint) {
  TrainParams p;
  p.methods = {MethodId::kUSH, MethodId::kVFH, MethodId::kFusion};
  std::vector<TrainingCloud> known = test::synthetic_views(5, 2, 11);
  std::erase_if(known, [](const TrainingCloud& c) { return c.category == "can"; });
  auto trained = train(known, p);
  ASSERT_TRUE(trained.ok()) << trained.error().message;
  const auto model = std::make_shared<const Model>(std::move(*trained));
  std::vector<Cloud> scans;
  for (const TrainingCloud& view : test::synthetic_views(1, 2, 82))
    if (view.category == "can") scans.push_back(view.cloud);
  Cloud sheet;
  for (int i = 0; i < 70; ++i)
    for (int j = 0; j < 70; ++j)
      sheet.points.emplace_back(0.03f * float(i), 0.03f * float(j), 0.1f * std::sin(0.3f * float(i)) + 0.002f * float(j));
  scans.push_back(sheet);
  bool sheet_settled_unknown = false;
  for (size_t k = 0; k < scans.size(); ++k) {
    const std::vector<Cloud> chunks = chunks_of(scans[k], 12, Order::kTopDown, 5);
    for (double acceptance : {0.0, 0.5, 1.0}) {
      SessionParams sp;
      sp.known_acceptance = acceptance;
      auto session = ScanSession::create(model, sp);
      ASSERT_TRUE(session.ok());
      for (const Cloud& c : chunks) {
        auto d = (*session)->add(c);
        ASSERT_TRUE(d.ok());
        if (k + 1 == scans.size() && acceptance == 0.0 && d->unknown && d->settled) sheet_settled_unknown = true;
      }
      auto d = (*session)->finish();
      ASSERT_TRUE(d.ok());
      auto whole = classify(*model, concatenated(chunks));
      ASSERT_TRUE(whole.ok());
      ASSERT_TRUE(set_known_acceptance(*model, *whole, acceptance).ok());
      EXPECT_EQ(d->unknown, whole->unknown) << k << " at " << acceptance;
      EXPECT_EQ(d->novelty, whole->novelty);
      EXPECT_EQ(d->winner, whole->winner);
      if (k + 1 == scans.size() && acceptance == 0.0) {
        EXPECT_TRUE(d->unknown) << "the sheet's novelty " << d->novelty;
      }
    }
  }
  EXPECT_TRUE(sheet_settled_unknown) << "\"unknown\" never settled on the sheet";
  SessionParams bad;
  bad.known_acceptance = 1.5;
  auto refused = ScanSession::create(model, bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
}

TEST(ScanSession, DuplicateOverlappingAndEmptyChunksChangeNothing) {
  const auto& model = fixed_radius_model();
  ASSERT_TRUE(model);
  const TrainingCloud view = test::synthetic_views(1, 1, 41)[1];
  const auto chunks = chunks_of(view.cloud, 6, Order::kTopDown, 0);
  SessionParams sp;
  sp.method = MethodId::kBoK;
  auto session = *ScanSession::create(model, sp);
  StreamDecision d;
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
  auto session = *ScanSession::create(model, {});
  const TrainingCloud view = test::synthetic_views(1, 1, 51)[0];
  auto first = session->add(Cloud{{view.cloud.points.begin(), view.cloud.points.begin() + 15}, view.cloud.sensor, {}});
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->winner, -1);  // fewer than FeatureParams::min_points (20)
  EXPECT_EQ(first->points, 15u);
  EXPECT_FALSE(first->settled);
  auto second = session->add(Cloud{{view.cloud.points.begin() + 15, view.cloud.points.begin() + 400}, view.cloud.sensor, {}});
  ASSERT_TRUE(second.ok());
  EXPECT_GE(second->winner, 0);
  EXPECT_EQ(second->chunk_index, 1u);
}

TEST(ScanSession, ALineStaysUndecided) {
  auto model = fixed_radius_model();
  ASSERT_TRUE(model);
  auto session = *ScanSession::create(model, {});
  for (int k = 0; k < 4; ++k) {
    Cloud chunk;
    for (int i = 0; i < 500; ++i) chunk.points.emplace_back(0.001f * float(500 * k + i), 0.f, 0.5f);
    auto d = session->add(chunk);
    ASSERT_TRUE(d.ok()) << d.error().message;
    EXPECT_EQ(d->winner, -1) << "chunk " << k;  // no surface, nothing to judge: no winner
    EXPECT_FALSE(d->settled);
  }
  auto end = session->finish();  // Classify of a line has nothing to judge: the scan ends in its error
  ASSERT_FALSE(end.ok());
  EXPECT_EQ(end.error().code, ErrorCode::kInvalidArgument) << end.error().message;
}

TEST(ScanSession, LimitsAndBadInput) {
  auto model = fixed_radius_model();
  ASSERT_TRUE(model);
  EXPECT_FALSE(ScanSession::create(nullptr).ok());
  EXPECT_EQ(ScanSession::create(std::make_shared<const Model>()).error().code, ErrorCode::kFailedPrecondition);

  SessionParams sp;
  sp.max_chunks = 3;
  sp.max_chunk_points = 100;
  sp.max_points = 150;
  auto session = *ScanSession::create(model, sp);
  Cloud far{{Vec3(0, 0, 0), Vec3(3e6f, 0, 0)}, std::nullopt, {}};
  auto bad = session->add(far);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("point 1 of chunk 0"), std::string::npos) << bad.error().message;
  Cloud nan{{Vec3(0, 0, 0), Vec3(NAN, 0, 0)}, std::nullopt, {}};  // dropped and counted, as extract() does
  auto dropped = session->add(nan);
  ASSERT_TRUE(dropped.ok()) << dropped.error().message;
  EXPECT_EQ(dropped->points, 1u);

  const TrainingCloud view = test::synthetic_views(1, 1, 61)[0];
  Cloud big{{view.cloud.points.begin(), view.cloud.points.begin() + 101}, std::nullopt, {}};
  EXPECT_EQ(session->add(big).error().code, ErrorCode::kResourceExhausted);
  Cloud ok{{view.cloud.points.begin(), view.cloud.points.begin() + 100}, view.cloud.sensor, {}};
  ASSERT_TRUE(session->add(ok).ok());
  Cloud more{{view.cloud.points.begin() + 100, view.cloud.points.begin() + 200}, view.cloud.sensor, {}};
  auto over = session->add(more);  // 101 held + 100 > 150: refused whole, never cut unsaid
  ASSERT_FALSE(over.ok());
  EXPECT_EQ(over.error().code, ErrorCode::kResourceExhausted);
  EXPECT_NE(over.error().message.find("chunk 2 of 100 points could take the session past its limit of 150"),
            std::string::npos) << over.error().message;
  EXPECT_NE(over.error().message.find("it holds 101"), std::string::npos) << over.error().message;
  // The session is as it was: a chunk that fits is taken, all of it.
  Cloud fits{{view.cloud.points.begin() + 100, view.cloud.points.begin() + 149}, view.cloud.sensor, {}};
  auto taken = session->add(fits);
  ASSERT_TRUE(taken.ok()) << taken.error().message;
  EXPECT_EQ(taken->chunk_index, 2u);
  EXPECT_LE(taken->points, 150u);
  EXPECT_GT(taken->points, 101u);

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

}  // namespace
}  // namespace glimpse
