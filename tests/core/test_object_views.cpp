// The protocol's views of one object and the training recipe (learning/object_views.h), and views under
// the scan conditions of real sensors (views/scan_conditions.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "glimpse/features/local_features.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/scan_conditions.h"
#include "glimpse/views/zoo.h"

namespace glimpse {
namespace {

TEST(ObjectViews, MedianDensityTakesThePositiveOnes) {
  EXPECT_EQ(median_density({0.0, 3.0, 1.0, -1.0, 2.0}), 2.0);
  EXPECT_EQ(median_density({4.0, 1.0, 3.0, 2.0}), 3.0);  // the upper of the middle two
  EXPECT_EQ(median_density({0.0, -2.0}), 0.0);
  EXPECT_EQ(median_density({}), 0.0);
}

// A sensor's training view is the camera's view filtered down to the ideal views' density; a camera that
// sees a sliver (a 1 cm object at 3 m: a few pixels) gives none, which training would refuse.
TEST(ObjectViews, SensorViewsAreThinnedToTheIdealDensityOrLeftOut) {
  const LabelledMesh o = make_zoo(1, 5).front();
  const std::string key = o.category + "/" + o.id;
  ScanCondition near;
  near.sensor = SensorKind::kDepthCamera, near.distance_m = 1.5f, near.elevation_deg = 15.f;
  ViewRecipe recipe;
  recipe.points = 3000, recipe.views = 3, recipe.seed = 7, recipe.train_sensors = {near};
  const uint64_t seed = object_seed(7, key);
  const Points full = full_cloud(o.mesh, key, recipe);
  EXPECT_EQ(full, object_cloud(o.mesh, 3000, seed));
  const std::vector<Cloud> ideal = ideal_views(full, key, o.any_pose, recipe);
  ASSERT_EQ(ideal.size(), 3u);
  const Cloud raw = condition_view(o.mesh, o.any_pose, full, 1, 3, seed, near, 3000, 100);
  const std::vector<Cloud> kept = sensor_views(o.mesh, full, key, o.any_pose, recipe, median_relative_density(ideal));
  ASSERT_EQ(kept.size(), 3u);
  ASSERT_GT(raw.points.size(), 2 * ideal[1].points.size()) << o.category;  // a camera at 1.5 m: dense
  EXPECT_GE(kept[1].points.size(), 40u) << o.category;
  EXPECT_LT(kept[1].points.size(), raw.points.size() / 2) << o.category;  // thinned towards the ideal density
  EXPECT_LT(relative_density(kept[1].points), 2.5 * relative_density(ideal[1].points)) << o.category;
  Mesh speck = o.mesh;  // the same object 1 cm across
  const Bounds b = bounds(speck.vertices);
  for (Vec3& p : speck.vertices) p = (p - b.min) * (0.01f / b.extent().maxCoeff());
  recipe.train_sensors[0].distance_m = 3.f;
  for (const Cloud& view : sensor_views(speck, full_cloud(speck, key, recipe), key, o.any_pose, recipe,
                                        median_relative_density(ideal)))
    EXPECT_TRUE(view.points.empty());
}

// What `glimpse train` sends and the lab learns of an object: the ideal views, then the cameras' views of
// the same azimuths (augmented), thinned to the density the model classifies at.
TEST(ObjectViews, TrainingViewsAreTheIdealOnesThenTheSensorsThinnedToTheDensity) {
  const LabelledMesh chair = make_zoo(1, 5).at(1);
  ASSERT_EQ(chair.category, "chair");
  const std::string key = "chair/" + chair.id;
  ViewRecipe recipe;
  recipe.points = 3000;
  const ObjectViews plain = training_views(chair.mesh, key, chair.any_pose, recipe, 0);
  EXPECT_EQ(plain.first_augmented, SIZE_MAX);
  ASSERT_EQ(plain.views.size(), 6u);
  const uint64_t seed = object_seed(recipe.seed, key);
  for (size_t v = 0; v < 6; ++v)
    EXPECT_EQ(plain.views[v].points, object_view(plain.full, v, 6, chair.any_pose, seed).points) << v;
  recipe.train_sensors = default_training_sensors();
  size_t thinned = 0, kept = 0;
  const std::vector<Cloud> unthinned = sensor_views(chair.mesh, plain.full, key, chair.any_pose, recipe, 0);
  for (double density : {0.0, median_relative_density(plain.views)}) {  // 0: not thinned
    const ObjectViews views = training_views(chair.mesh, key, chair.any_pose, recipe, density);
    const size_t sensors = recipe.train_sensors.size();
    ASSERT_EQ(views.views.size(), 6 * (1 + sensors));
    EXPECT_EQ(views.first_augmented, 6u);
    for (size_t v = 0; v < 6; ++v) {
      EXPECT_EQ(views.views[v].points, plain.views[v].points);
      for (size_t s = 0; s < sensors; ++s) {
        ScanFilterParams filters;
        filters.relative_density = density;
        Cloud expected = filter_scan(condition_view(chair.mesh, chair.any_pose, plain.full, v, 6, seed,
                                                    recipe.train_sensors[s], 3000, 100),
                                     filters);
        if (expected.points.size() < 2 * FeatureParams{}.min_points) expected.points.clear();  // left out
        else ++kept;
        EXPECT_EQ(views.views[6 * (s + 1) + v].points, expected.points) << "sensor " << s << " view " << v;
        if (density > 0) thinned += expected.points.size() < unthinned[6 * s + v].points.size();
      }
    }
  }
  EXPECT_GE(thinned, 6u);    // the depth camera's views at least
  EXPECT_GE(kept, 2 * 20u);  // of 2 x 36: the depth camera's and some of the LiDARs'
}

// A range of poses: each view draws its own distance and elevation in the range, the same on every run;
// another draw of the same range gives other poses; a negative elevation never puts the sensor under the
// ground.
TEST(TrainingSensors, RangesDrawEachViewsPoseWithinThemAndNeverBelowTheGround) {
  const LabelledMesh table = make_zoo(1, 5).at(2);
  ASSERT_EQ(table.category, "table");
  auto drawn = parse_training_sensors("depth:0.8-4:-10-60,depth:0.8-4:-10-60");
  ASSERT_TRUE(drawn.ok());
  const Vec3 centre = bounds(table.mesh.vertices).centre();
  std::vector<float> distances, elevations;
  for (const ScanCondition& c : *drawn)
    for (size_t v = 0; v < 6; ++v) {
      const Cloud view = condition_view(table.mesh, false, {}, v, 6, 99, c, 3000, 100);
      ASSERT_TRUE(view.sensor.has_value());
      EXPECT_EQ(*view.sensor, *condition_view(table.mesh, false, {}, v, 6, 99, c, 3000, 100).sensor);
      const Vec3 d = *view.sensor - centre;
      distances.push_back(d.norm());
      elevations.push_back(std::asin(d.z() / d.norm()) * 180.f / float(M_PI));
      EXPECT_GE(view.sensor->z(), -1e-4f);
      EXPECT_FALSE(view.points.empty());
    }
  for (size_t i = 0; i < distances.size(); ++i) {
    EXPECT_GE(distances[i], 0.8f - 1e-4f);
    EXPECT_LE(distances[i], 4.f + 1e-4f);
    EXPECT_GE(elevations[i], -10.f - 1e-3f);
    EXPECT_LE(elevations[i], 60.f + 1e-3f);
  }
  // Twelve draws spread over the ranges (not one pose repeated).
  EXPECT_GT(*std::max_element(distances.begin(), distances.end()) - *std::min_element(distances.begin(), distances.end()), 1.5f);
  EXPECT_GT(*std::max_element(elevations.begin(), elevations.end()) - *std::min_element(elevations.begin(), elevations.end()), 30.f);
  EXPECT_NE(distances[0], distances[6]);  // the second draw of view 0
}

TEST(TrainingSensors, ParseAndSpecRoundTripAndBadItemsAreNamed) {
  auto d = parse_training_sensors(training_sensors_spec(default_training_sensors()));
  ASSERT_TRUE(d.ok()) << d.error().message;
  EXPECT_EQ(*d, default_training_sensors());
  EXPECT_EQ(training_sensors_spec(default_training_sensors()),
            "depth:0.8-4:-10-60,depth:0.8-4:-10-60,depth:0.8-4:-10-60,lidar:5-20:5,lidar32:5-20:5,lidar64:5-20:5");
  auto l = parse_training_sensors("lidar:8:5");
  ASSERT_TRUE(l.ok());
  ASSERT_EQ(l->size(), 1u);
  EXPECT_EQ((*l)[0].sensor, SensorKind::kLidar);
  EXPECT_FLOAT_EQ((*l)[0].distance_m, 8.f);
  EXPECT_FLOAT_EQ((*l)[0].elevation_deg, 5.f);
  auto wide = parse_training_sensors("lidar64:20:5,lidar32:10:5,lidar16:5:5");
  ASSERT_TRUE(wide.ok()) << wide.error().message;
  ASSERT_EQ(wide->size(), 3u);
  EXPECT_EQ((*wide)[0].beams, 64);
  EXPECT_EQ((*wide)[1].beams, 32);
  EXPECT_EQ((*wide)[2].beams, 16);
  EXPECT_EQ(training_sensors_spec(*wide), "lidar64:20:5,lidar32:10:5,lidar:5:5");
  EXPECT_EQ(describe((*wide)[1]), "LiDAR 32 beams 10 m, 5 deg");
  auto ranges = parse_training_sensors("depth:0.8-4:-10-60,depth:0.8-4:-10-60,lidar:5-20:5");
  ASSERT_TRUE(ranges.ok()) << ranges.error().message;
  ASSERT_EQ(ranges->size(), 3u);
  EXPECT_FLOAT_EQ((*ranges)[0].distance_m, 0.8f);
  EXPECT_FLOAT_EQ((*ranges)[0].distance_to_m, 4.f);
  EXPECT_FLOAT_EQ((*ranges)[0].elevation_deg, -10.f);
  EXPECT_FLOAT_EQ((*ranges)[0].elevation_to_deg, 60.f);
  EXPECT_EQ((*ranges)[0].draw, 0);
  EXPECT_EQ((*ranges)[1].draw, 1);  // listed again: another draw
  EXPECT_EQ((*ranges)[2].draw, 0);
  EXPECT_EQ(training_sensors_spec(*ranges), "depth:0.8-4:-10-60,depth:0.8-4:-10-60,lidar:5-20:5");
  EXPECT_EQ(describe((*ranges)[0]), "depth camera 0.8-4 m, -10-60 deg");
  EXPECT_EQ(describe(*ranges), "depth camera 0.8-4 m, -10-60 deg (2 draws); LiDAR 16 beams 5-20 m, 5 deg");
  auto none = parse_training_sensors("none");
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->empty());
  EXPECT_EQ(training_sensors_spec({}), "none");
  for (const char* bad : {"", "depth", "depth:2", "ideal:2:30", "depth:-1:30", "depth:2:95", "depth:2:30,x", "cam:2:30", "lidar8:5:5",
                          "lidar128:5:5", "depth:4-0.8:0", "depth:0.8-:0", "depth:-1-4:0", "depth:2:-10-95", "depth:2:60-10"}) {
    auto r = parse_training_sensors(bad);
    EXPECT_FALSE(r.ok()) << bad;
    if (!r.ok() && std::string(bad).size() > 0) {
      EXPECT_NE(r.error().message.find("not '"), std::string::npos) << r.error().message;
    }
  }
}

}  // namespace
}  // namespace glimpse
