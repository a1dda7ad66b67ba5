// The views of one object the protocol makes (sec. 3.4) and the training recipe: its full 3D cloud, the
// paper's single views from its six viewpoints, the same azimuths from other elevations, and the same
// azimuths seen by simulated sensors, thinned to the density the model classifies at. `glimpse train`,
// `glimpse evaluate` and the lab make every object's views with these functions, so a folder trained
// through the service is learnt as the lab learns it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/views/scan_conditions.h"

namespace glimpse {

struct ViewRecipe {
  size_t points = 6000;            // surface samples per object (0: the mesh's vertices, as the paper)
  size_t views = 6;                // evenly spaced among the paper's 6 viewpoints; 0: the whole sampled cloud
  double hpr_radius_factor = 100;  // hidden point removal's radius (views/hidden_point_removal.h)
  uint64_t seed = 42;              // samples and poses, with the object's name (object_seed)
  // Training only: more views of the same azimuths from these elevations (deg above the horizon), so a
  // model learns cameras mounted low or high.
  std::vector<float> train_elevations_deg;
  // Training only: more views of the same azimuths taken by these simulated sensors, through `filters`
  // down to the density the model classifies at (default_training_sensors: the recipe's).
  std::vector<ScanCondition> train_sensors;
  ScanFilterParams filters;
};

// The recipe's training sensors (glimpse-lab --train-sensors, glimpse train --sensor-views), the poses
// real scanners take: "depth:0.8-4:-10-60" three times (each view of each draw a depth camera 0.8-4 m
// away, -10 to 60 deg up; close views cut by the frame) and "lidar:5-20:5,lidar32:5-20:5,lidar64:5-20:5"
// (LiDAR of 16, 32 and 64 beams 5-20 m away). docs/sensors.md measures it.
std::vector<ScanCondition> default_training_sensors();

// The object's full 3D cloud: recipe.points area-weighted samples seeded by (recipe.seed, `key`), or its
// vertices when points is 0 or the mesh has no area; non-finite points dropped. `key` is "category/id".
Points full_cloud(const Mesh& mesh, std::string_view key, const ViewRecipe& recipe);

// The ideal views of an object (its mesh upright, real-life size, on the ground): the paper's recipe.views
// views of `full`, then the same azimuths from each of recipe.train_elevations_deg. recipe.views 0: the
// whole cloud as one view. An object without a natural up (`any_pose`) is seen in a random pose per view.
std::vector<Cloud> ideal_views(const Points& full, std::string_view key, bool any_pose, const ViewRecipe& recipe);

// The training sensors' views of the object (recipe.train_sensors x recipe.views, sensor-major), each
// through recipe.filters down to `density`, the relative density the model classifies at (0: not thinned).
// A view of which a sensor saw fewer than 2 x FeatureParams::min_points points is empty: a view of a
// sliver teaches nothing, and training refuses a whole cloud without features.
std::vector<Cloud> sensor_views(const Mesh& mesh, const Points& full, std::string_view key, bool any_pose,
                                const ViewRecipe& recipe, double density);

// Every view a model learns of one object: the ideal views, then the sensors' (the augmented ones, from
// first_augmented on; TrainingCloud::augmented).
struct ObjectViews {
  Points full;                        // the object's full 3D cloud: a stage's fraction is of its size
  std::vector<Cloud> views;
  size_t first_augmented = SIZE_MAX;  // no sensor views: SIZE_MAX
};
ObjectViews training_views(const Mesh& mesh, std::string_view key, bool any_pose, const ViewRecipe& recipe,
                           double density);

// The density pass: the median of the positive relative densities (geometry/scan_filters.h); 0 when none
// is. The density a model classifies at is this median over its training objects' ideal views.
double median_density(std::vector<double> densities);
// The median relative density of `views`, those with one; 0 when none has.
double median_relative_density(const std::vector<Cloud>& views);

}  // namespace glimpse
