// A scan fused from several sensor positions: each point's normal faces the sensor that saw it
// (extract_fused), a filtering model decides a scan of several views view by view, and a stream's final
// decision over chunks from several sensors is Classify's of the scan with each point's own sensor
// (classify_fused), filtered or not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "glimpse/features/local_features.h"
#include "glimpse/session/session.h"
#include "glimpse/learning/train_params.h"
#include "synthetic.h"

namespace glimpse {
namespace {

// A sphere of radius 0.3 m about (0, 0, 1), evenly sampled (Fibonacci lattice): what a sensor 2 m out
// on +x sees (its cap x > r^2 / 2 m), then what one on -x sees; the band neither sees is not scanned.
struct TwoSidedScan {
  Cloud front, back;
  Vec3 centre{0, 0, 1};
};

TwoSidedScan sphere_from_both_sides(size_t n = 6000) {
  TwoSidedScan s;
  s.front.sensor = s.centre + Vec3(2, 0, 0);
  s.back.sensor = s.centre + Vec3(-2, 0, 0);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(n), r = std::sqrt(1.0 - z * z), a = golden * double(i);
    const Vec3 p = s.centre + 0.3f * Vec3(float(r * std::cos(a)), float(r * std::sin(a)), float(z));
    const Vec3 n = (p - s.centre).normalized();
    if (n.dot(*s.front.sensor - p) > 0) s.front.points.push_back(p);
    else if (n.dot(*s.back.sensor - p) > 0) s.back.points.push_back(p);
  }
  return s;
}

Cloud fused(const TwoSidedScan& s, std::vector<std::optional<Vec3>>& sensors) {
  Cloud all;
  all.sensor = s.back.sensor;  // the latest chunk's
  for (const Cloud* c : {&s.front, &s.back})
    for (const Vec3& p : c->points) all.points.push_back(p), sensors.push_back(c->sensor);
  return all;
}

// A USH model of the synthetic shapes, with the scan filters or without.
Expected<Model> ush_model(bool filter_scans = true) {
  TrainParams p;
  p.methods = {MethodId::kUSH};
  p.default_method = MethodId::kUSH;
  p.filter_scans = filter_scans;
  return train(test::synthetic_views(3, 2, 5), p);
}

// Outward share of the valid normals among the points of one half.
double outward_share(const FeatureState& st, const Vec3& centre, bool front) {
  size_t out = 0, n = 0;
  for (size_t i = 0; i < st.cloud.points.size(); ++i) {
    const Vec3& p = st.cloud.points[i];
    if (!st.surfaces[i].valid || (p.x() > 0) != front) continue;
    ++n;
    out += st.surfaces[i].normal.dot(p - centre) > 0;
  }
  return n ? double(out) / double(n) : 0.0;
}

FeatureParams params() {
  FeatureParams p;
  p.surface.threads = 1;
  return p;
}

TEST(ExtractFused, EachPointFacesTheSensorThatSawIt) {
  const TwoSidedScan s = sphere_from_both_sides();
  std::vector<std::optional<Vec3>> sensors;
  const Cloud all = fused(s, sensors);
  auto st = extract_fused(all, sensors, params());
  ASSERT_TRUE(st.ok()) << st.error().message;
  // Both halves point out of the sphere: each faces its own sensor.
  EXPECT_GT(outward_share(*st, s.centre, true), 0.99);
  EXPECT_GT(outward_share(*st, s.centre, false), 0.99);
  // One sensor for the whole scan (the latest, on -x: what a fused cloud with one viewpoint gets) turns
  // the half it did not see inward.
  auto one = extract(all, params());
  ASSERT_TRUE(one.ok());
  EXPECT_LT(outward_share(*one, s.centre, true), 0.01);
  EXPECT_GT(outward_share(*one, s.centre, false), 0.99);
  // It is what a stream of the two chunks holds, bit for bit.
  ScanFeatures scan(params());
  ASSERT_TRUE(scan.add(s.front).ok());
  ASSERT_TRUE(scan.add(s.back).ok());
  EXPECT_EQ(scan.viewpoints(), sensors);
  ASSERT_EQ(scan.state().cloud.points, st->cloud.points);
  for (size_t i = 0; i < st->surfaces.size(); ++i) ASSERT_EQ(scan.state().surfaces[i].normal, st->surfaces[i].normal) << i;
}

TEST(ExtractFused, OneSensorIsExtractAndEveryPointNeedsOne) {
  const TwoSidedScan s = sphere_from_both_sides(3000);
  const std::vector<std::optional<Vec3>> sensors(s.front.points.size(), s.front.sensor);
  Cloud no_sensor = s.front;
  no_sensor.sensor.reset();
  auto a = extract_fused(no_sensor, sensors, params());
  auto b = extract(s.front, params());
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->surfaces.size(), b->surfaces.size());
  for (size_t i = 0; i < a->surfaces.size(); ++i) ASSERT_EQ(a->surfaces[i].normal, b->surfaces[i].normal) << i;
  auto bad = extract_fused(s.front, std::vector<std::optional<Vec3>>(3, s.front.sensor), params());
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("one sensor per point"), std::string::npos) << bad.error().message;
}

// A ball seen from two sides streamed as two chunks: the final decision is classify_fused's of the two
// halves with their own sensors, with the scan filters and without; classify() of the same points with
// the one latest sensor reads other normals and gives other scores.
TEST(ScanSession, TheFinalDecisionOfChunksFromSeveralSensorsFacesEachChunksSensor) {
  for (bool filter : {true, false}) {
    SCOPED_TRACE(filter ? "filtered" : "unfiltered");
    auto model = ush_model(filter);
    ASSERT_TRUE(model.ok()) << model.error().message;
    const auto shared = std::make_shared<const Model>(std::move(*model));
    const TwoSidedScan s = sphere_from_both_sides();
    auto session = ScanSession::create(shared, {});
    ASSERT_TRUE(session.ok());
    ASSERT_TRUE((*session)->add(s.front).ok());
    ASSERT_TRUE((*session)->add(s.back).ok());
    auto d = (*session)->finish();
    ASSERT_TRUE(d.ok()) << d.error().message;
    ASSERT_TRUE(d->final);
    std::vector<std::optional<Vec3>> sensors;
    const Cloud all = fused(s, sensors);
    auto c = classify_fused(*shared, all, sensors);
    ASSERT_TRUE(c.ok()) << c.error().message;
    EXPECT_EQ(d->raw_scores, c->scores);
    EXPECT_EQ(d->points, c->points);
    auto one = classify(*shared, all);
    ASSERT_TRUE(one.ok());
    EXPECT_NE(one->scores, c->scores);
  }
}

// Every model learns single views: a filtering model decides a scan of several views (sensors looking
// from more than 30 degrees apart) view by view and joins the answers (the mean of their scores), and a
// second sensor beside the first (20 degrees) is the same view: the scan is decided as one.
TEST(ClassifyFused, AScanOfSeveralViewsIsDecidedViewByView) {
  auto model = ush_model();
  ASSERT_TRUE(model.ok()) << model.error().message;
  const TwoSidedScan s = sphere_from_both_sides();
  std::vector<std::optional<Vec3>> sensors;
  const Cloud all = fused(s, sensors);
  auto joined = classify_fused(*model, all, sensors);
  auto front = classify(*model, s.front), back = classify(*model, s.back);
  ASSERT_TRUE(joined.ok() && front.ok() && back.ok()) << joined.error().message;
  ASSERT_EQ(joined->scores.size(), front->scores.size());
  for (size_t k = 0; k < joined->scores.size(); ++k)
    EXPECT_EQ(joined->scores[k], front->scores[k] / 2 + back->scores[k] / 2) << k;
  EXPECT_EQ(joined->points, front->points + back->points);
  EXPECT_EQ(joined->winner, int(std::max_element(joined->scores.begin(), joined->scores.end()) - joined->scores.begin()));

  // The back's points seen from 20 degrees beside the front's sensor: one view, the fused scan's answer.
  const Vec3 beside = s.centre + 2.f * Vec3(std::cos(0.35f), std::sin(0.35f), 0.f);
  std::vector<std::optional<Vec3>> near = sensors;
  for (size_t i = s.front.points.size(); i < near.size(); ++i) near[i] = beside;
  Cloud one_view = all;
  one_view.sensor = beside;
  auto single = classify_fused(*model, one_view, near);
  ASSERT_TRUE(single.ok()) << single.error().message;
  EXPECT_NE(single->scores, joined->scores);
  EXPECT_EQ(single->points, joined->points);  // ... of the same points, filtered as one cloud

  // A model without filters fuses the points of every view.
  auto plain = ush_model(false);
  ASSERT_TRUE(plain.ok());
  auto fused_scan = classify_fused(*plain, all, sensors);
  auto plain_front = classify(*plain, s.front), plain_back = classify(*plain, s.back);
  ASSERT_TRUE(fused_scan.ok() && plain_front.ok() && plain_back.ok());
  EXPECT_NE(fused_scan->scores[0], plain_front->scores[0] / 2 + plain_back->scores[0] / 2);
}

// A model that filters its scans decides every chunk on the scan so far, filtered as a whole: each
// chunk's raw scores are classify_fused's of the points sent so far with their chunks' sensors, whether
// the filters take nothing (ScanFeatures grown chunk by chunk) or a floor that came last (Classify's of
// the filtered scan). USH is recomputed every chunk, so the two agree bit for bit.
TEST(ScanSession, AFilteringModelDecidesEveryChunkOnTheWholeScanSoFar) {
  auto model = ush_model();
  ASSERT_TRUE(model.ok()) << model.error().message;
  ASSERT_TRUE(model->impl);
  const auto shared = std::make_shared<const Model>(std::move(*model));
  const TwoSidedScan s = sphere_from_both_sides();
  Cloud floor;  // 1.6 m square under the ball (z = 0.7), 1 cm grid, seen by the second sensor
  floor.sensor = s.back.sensor;
  for (int i = 0; i <= 160; ++i)
    for (int j = 0; j <= 160; ++j) floor.points.emplace_back(-0.8f + 0.01f * float(i), -0.8f + 0.01f * float(j), 0.7f);
  auto session = ScanSession::create(shared, {});
  ASSERT_TRUE(session.ok());
  Cloud so_far;
  std::vector<std::optional<Vec3>> sensors;
  size_t decided = 0;
  size_t ground = 0, unfiltered = 0, filtered = 0;  // chunks the filters left alone / changed
  // The front in chunks; the back (a second view: from then on the scan is decided view by view, again
  // when it has grown by global_refresh_growth) and its floor one chunk each, so each is decided anew.
  for (const Cloud* half : std::initializer_list<const Cloud*>{&s.front, &s.back, &floor})
    for (size_t begin = 0, step = half == &s.front ? 350 : 30000; begin < half->points.size(); begin += step) {
      Cloud chunk;
      chunk.sensor = half->sensor;
      for (size_t i = begin; i < std::min(begin + step, half->points.size()); ++i) {
        chunk.points.push_back(half->points[i]);
        so_far.points.push_back(half->points[i]);
        sensors.push_back(half->sensor);
      }
      so_far.sensor = half->sensor;
      auto d = (*session)->add(chunk);
      ASSERT_TRUE(d.ok()) << d.error().message;
      auto c = classify_fused(*shared, so_far, sensors);
      if (!c.ok()) {
        EXPECT_EQ(d->winner, -1);  // undecided while Classify cannot decide either
        continue;
      }
      ++decided;
      ground = c->filters.ground;
      (c->filters.kept == c->filters.input && c->filters.voxel_m == 0 ? unfiltered : filtered) += 1;
      EXPECT_EQ(d->raw_scores, c->scores) << "after " << so_far.points.size() << " points";
      EXPECT_EQ(d->points, so_far.points.size());
    }
  EXPECT_GE(decided, 8u);
  EXPECT_GE(unfiltered, 7u);  // the ball alone: ScanFeatures grown chunk by chunk
  EXPECT_GE(filtered, 1u);    // the floor: Classify's of the filtered scan
  // The last decision saw the floor and the filters took it, with the ball's cap within the inlier
  // distance (4 cm: about 4 % of the ball's points).
  EXPECT_GE(ground, floor.points.size());
  EXPECT_LT(ground, floor.points.size() + (s.front.points.size() + s.back.points.size()) / 15);
}

}  // namespace
}  // namespace glimpse
