// ScanSession: streaming a view chunk by chunk ends where classifying the whole view does; duplicates
// and empty chunks change nothing; the decision track counts changes and settles as specified.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "glimpse/features/local_features.h"
#include "glimpse/session/session.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/views/exploration.h"
#include "shapes.h"
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

const std::shared_ptr<const Model>& automatic_radius_model() {
  static const auto m = trained_model(0);
  return m;
}

enum class Order { kTopDown, kRandom, kSweep };

// The view's points in the given order, cut into chunks of random sizes (about `n` chunks, seeded).
std::vector<Cloud> chunks_of(const Cloud& view, size_t n, Order order_kind, uint64_t seed, bool sensor = true) {
  std::vector<uint32_t> order(view.points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937_64 rng(seed);
  if (order_kind == Order::kRandom) {
    for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  } else if (order_kind == Order::kTopDown) {
    order = top_down_order(view.points);
  } else {  // a sweep along x, as a scanner passing by
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return view.points[a].x() < view.points[b].x(); });
  }
  std::vector<Cloud> out;
  for (size_t i = 0; i < order.size();) {
    const size_t mean = std::max<size_t>(1, order.size() / std::max<size_t>(1, n));
    const size_t size = n == 1 ? order.size() : 1 + rng() % (2 * mean);
    Cloud c;
    if (sensor) c.sensor = view.sensor;
    for (size_t k = 0; k < size && i < order.size(); ++k, ++i) c.points.push_back(view.points[order[i]]);
    out.push_back(std::move(c));
  }
  return out;
}

Cloud concatenated(const std::vector<Cloud>& chunks) {
  Cloud all;
  for (const Cloud& c : chunks) {
    all.points.insert(all.points.end(), c.points.begin(), c.points.end());
    if (c.sensor) all.sensor = c.sensor;
  }
  return all;
}

void expect_same_state(const FeatureState& a, const FeatureState& b) {
  ASSERT_EQ(a.cloud.points, b.cloud.points);
  EXPECT_EQ(a.diagnostics.support_radius_m, b.diagnostics.support_radius_m);
  EXPECT_EQ(a.diagnostics.density.knn_distance_m, b.diagnostics.density.knn_distance_m);
  ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
  for (size_t i = 0; i < a.surfaces.size(); ++i) {
    ASSERT_EQ(a.surfaces[i].valid, b.surfaces[i].valid) << "point " << i;
    EXPECT_EQ(a.surfaces[i].normal, b.surfaces[i].normal) << "point " << i;
    EXPECT_EQ(a.surfaces[i].k1, b.surfaces[i].k1) << "point " << i;
    EXPECT_EQ(a.surfaces[i].k2, b.surfaces[i].k2) << "point " << i;
    EXPECT_EQ(a.surfaces[i].lambda_min, b.surfaces[i].lambda_min) << "point " << i;
    EXPECT_EQ(a.surfaces[i].harris_response, b.surfaces[i].harris_response) << "point " << i;
  }
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (size_t k = 0; k < a.keypoints.size(); ++k) {
    EXPECT_EQ(a.keypoints[k].index, b.keypoints[k].index) << "keypoint " << k;
    EXPECT_EQ(a.descriptors[k], b.descriptors[k]) << "keypoint " << k;
  }
}

// The invariant: however a cloud arrives — any chunking, top-down, random or sweep order, with or
// without a sensor, automatic or fixed radius — a scan ends on the state extract() gives the
// accumulated cloud, bit for bit (both visit neighbourhoods in index order).
TEST(ScanFeatures, EndOnTheStateExtractGivesTheAccumulatedCloud) {
  const std::vector<TrainingCloud> views = test::synthetic_views(1, 1, 71);
  for (float radius : {0.f, 0.025f}) {
    FeatureParams params;
    params.surface.support_radius_m = radius;
    params.surface.threads = 1;
    for (const TrainingCloud& view : views)
      for (bool sensor : {true, false})
        for (Order order : {Order::kTopDown, Order::kRandom, Order::kSweep})
          for (size_t n : {1u, 3u, 17u}) {
            SCOPED_TRACE(view.category + (sensor ? " with" : " without") + " a sensor, order " +
                         std::to_string(int(order)) + ", ~" + std::to_string(n) + " chunks, r " + std::to_string(radius));
            const std::vector<Cloud> chunks = chunks_of(view.cloud, n, order, 7 * n + size_t(order), sensor);
            ScanFeatures scan(params);
            for (const Cloud& c : chunks) ASSERT_TRUE(scan.add(c).ok());
            ASSERT_TRUE(scan.ready());
            auto whole = extract(concatenated(chunks), params);
            ASSERT_TRUE(whole.ok()) << whole.error().message;
            expect_same_state(scan.state(), *whole);
            EXPECT_FALSE(scan.state().keypoints.empty());
          }
  }
}

// The same with the keypoint options of the paper preset and its ablation (no rho1 cap, claims of rho1, a
// boundary band of 0, 0.5 or 1.5 r, a boundary test over 2 r, the Harris response, descriptors at rho1): what a chunk changes
// reaches every memo entry it must.
TEST(ScanFeatures, KeypointOptionsEndOnTheStateExtractGives) {
  // A box corner and a ball, seen from one side: corners, curved patches and a view boundary.
  Cloud scene{test::jitter(test::cube(0.3f, 0.008f), 0.0005f, 5), Vec3(1.2f, 0.9f, 1.1f)};
  for (const Vec3& p : test::sphere(0.1f, 3000, Vec3(0.5f, 0.15f, 0.1f))) scene.points.push_back(p);
  struct Option {
    const char* name;
    float band, boundary_radius;
    KeypointResponse response;
    float descriptor_scale = 0;
  };
  for (const Option& o : {Option{"band 0", 0.f, 1.f, KeypointResponse::kLambdaMin},
                          Option{"band 0.5, boundary over 2 r", 0.5f, 2.f, KeypointResponse::kLambdaMin},
                          Option{"band 1.5", 1.5f, 1.f, KeypointResponse::kLambdaMin},
                          Option{"band 0, boundary over 2 r, Harris", 0.f, 2.f, KeypointResponse::kHarris},
                          Option{"band 0.5, described over rho1 up to 4 r", 0.5f, 1.f, KeypointResponse::kLambdaMin, 4.f}}) {
    FeatureParams params;
    params.surface.threads = 1;
    params.surface.support_radius_m = 0.02f;  // fixed: every chunk takes the incremental path
    params.keypoints.max_radius_supports = 0;
    params.keypoints.claim_min_supports = 0;
    params.keypoints.boundary_band_supports = o.band;
    params.keypoints.boundary_radius_supports = o.boundary_radius;
    params.keypoints.response = o.response;
    params.descriptor.characteristic_scale_supports = o.descriptor_scale;
    size_t keypoints = 0;
    for (Order order : {Order::kRandom, Order::kTopDown})
        for (size_t n : {17u}) {
          SCOPED_TRACE(std::string(o.name) + ", order " + std::to_string(int(order)) + ", ~" + std::to_string(n) + " chunks");
          const std::vector<Cloud> chunks = chunks_of(scene, n, order, 5 * n + size_t(order), true);
          // After every chunk, not only the last: a stale memo entry shows as soon as it matters.
          ScanFeatures scan(params);
          std::vector<Cloud> so_far;
          for (const Cloud& c : chunks) {
            ASSERT_TRUE(scan.add(c).ok());
            so_far.push_back(c);
            if (!scan.ready()) continue;
            auto whole = extract(concatenated(so_far), params);
            ASSERT_TRUE(whole.ok()) << whole.error().message;
            expect_same_state(scan.state(), *whole);
            if (HasFailure()) return;
            keypoints += whole->keypoints.size();
          }
        }
    EXPECT_GT(keypoints, 0u) << o.name;
  }
}

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
  EXPECT_GE(whole->filters.outliers, 1u);  // was 0: the copies were the stray point's neighbours
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

// A model that does not filter scans (one written before the filters) ends a stream as Classify does
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
  auto first = session->add(Cloud{{view.cloud.points.begin(), view.cloud.points.begin() + 15}, view.cloud.sensor});
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->winner, -1);  // fewer than FeatureParams::min_points (20)
  EXPECT_EQ(first->points, 15u);
  EXPECT_FALSE(first->settled);
  auto second = session->add(Cloud{{view.cloud.points.begin() + 15, view.cloud.points.begin() + 400}, view.cloud.sensor});
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
  Cloud far{{Vec3(0, 0, 0), Vec3(3e6f, 0, 0)}, std::nullopt};
  auto bad = session->add(far);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("point 1 of chunk 0"), std::string::npos) << bad.error().message;
  Cloud nan{{Vec3(0, 0, 0), Vec3(NAN, 0, 0)}, std::nullopt};  // dropped and counted, as extract() does
  auto dropped = session->add(nan);
  ASSERT_TRUE(dropped.ok()) << dropped.error().message;
  EXPECT_EQ(dropped->points, 1u);

  const TrainingCloud view = test::synthetic_views(1, 1, 61)[0];
  Cloud big{{view.cloud.points.begin(), view.cloud.points.begin() + 101}, std::nullopt};
  EXPECT_EQ(session->add(big).error().code, ErrorCode::kResourceExhausted);
  Cloud ok{{view.cloud.points.begin(), view.cloud.points.begin() + 100}, view.cloud.sensor};
  ASSERT_TRUE(session->add(ok).ok());
  Cloud more{{view.cloud.points.begin() + 100, view.cloud.points.begin() + 200}, view.cloud.sensor};
  auto over = session->add(more);  // 101 held + 100 > 150: refused whole, never cut unsaid
  ASSERT_FALSE(over.ok());
  EXPECT_EQ(over.error().code, ErrorCode::kResourceExhausted);
  EXPECT_NE(over.error().message.find("chunk 2 of 100 points could take the session past its limit of 150"),
            std::string::npos) << over.error().message;
  EXPECT_NE(over.error().message.find("it holds 101"), std::string::npos) << over.error().message;
  // The session is as it was: a chunk that fits is taken, all of it.
  Cloud fits{{view.cloud.points.begin() + 100, view.cloud.points.begin() + 149}, view.cloud.sensor};
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
  p.unsettle_margin = 1.0;
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
  SessionParams p;
  p.smoothing = 0.5;
  p.stability_window = 4;
  p.full_margin = 0.1;
  p.settle_confidence = 0.5;
  DecisionTrack t;
  auto step = [&](std::vector<double> s) {
    track_decision(t, s, 0, false, p);
    return t.decision;
  };
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
