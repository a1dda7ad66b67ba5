// ScanFeatures: however a cloud arrives chunk by chunk, the scan ends on the state extract() gives the
// accumulated cloud, bit for bit, with the default keypoint options and the paper preset's.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "chunks.h"
#include "glimpse/features/local_features.h"
#include "shapes.h"
#include "synthetic.h"

namespace glimpse {
namespace {

using test::chunks_of;
using test::concatenated;
using test::Order;

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
  Cloud scene{test::jitter(test::cube(0.3f, 0.008f), 0.0005f, 5), Vec3(1.2f, 0.9f, 1.1f), {}};
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

}  // namespace
}  // namespace glimpse
