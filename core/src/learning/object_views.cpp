// The views of one object the protocol makes and the training recipe (sec. 3.4).
#include "glimpse/learning/object_views.h"

#include <algorithm>
#include <string>

#include "glimpse/features/local_features.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/sampling.h"

namespace glimpse {

namespace {

// A training-only view of a simulated sensor: condition_view through `filters` down to `trained_density`.
Cloud sensor_view(const Mesh& mesh, bool any_pose, const Points& full, size_t view, size_t views, uint64_t seed,
                  const ScanCondition& condition, size_t points_per_object, double hpr_radius_factor,
                  double trained_density, ScanFilterParams filters) {
  filters.relative_density = trained_density;
  Cloud cloud = filter_scan(condition_view(mesh, any_pose, full, view, views, seed, condition, points_per_object, hpr_radius_factor),
                            filters);
  // A camera that sees a sliver of the object (too close, or past its far end) teaches nothing, and
  // training refuses a whole cloud without features: such a view is left out (empty).
  if (cloud.points.size() < 2 * FeatureParams{}.min_points) return Cloud{};
  return cloud;
}

}  // namespace

std::vector<ScanCondition> default_training_sensors() {
  std::vector<ScanCondition> out;
  ScanCondition camera;  // three draws of a pose in the depth camera's range
  camera.sensor = SensorKind::kDepthCamera;
  camera.distance_m = 0.8f, camera.distance_to_m = 4.f, camera.elevation_deg = -10.f, camera.elevation_to_deg = 60.f;
  for (int draw = 0; draw < 3; ++draw) out.push_back(camera), out.back().draw = draw;
  for (int beams : {16, 32, 64}) {  // one draw of each LiDAR class
    ScanCondition lidar;
    lidar.sensor = SensorKind::kLidar, lidar.beams = beams;
    lidar.distance_m = 5.f, lidar.distance_to_m = 20.f, lidar.elevation_deg = 5.f;
    out.push_back(lidar);
  }
  return out;
}

Points full_cloud(const Mesh& mesh, std::string_view key, const ViewRecipe& recipe) {
  Points full = object_cloud(mesh, recipe.points, object_seed(recipe.seed, key));
  std::erase_if(full, [](const Vec3& p) { return !p.allFinite(); });
  return full;
}

std::vector<Cloud> ideal_views(const Points& full, std::string_view key, bool any_pose, const ViewRecipe& recipe) {
  if (recipe.views == 0) return {Cloud{full, std::nullopt, {}}};
  const uint64_t seed = object_seed(recipe.seed, key);
  std::vector<Cloud> out;
  for (size_t v = 0; v < recipe.views; ++v)
    out.push_back(object_view(full, v, recipe.views, any_pose, seed, recipe.hpr_radius_factor));
  for (float elevation : recipe.train_elevations_deg)
    if (elevation != kPaperElevationDeg)
      for (size_t v = 0; v < recipe.views; ++v)
        out.push_back(object_view(full, v, recipe.views, any_pose, seed, recipe.hpr_radius_factor, elevation));
  return out;
}

std::vector<Cloud> sensor_views(const Mesh& mesh, const Points& full, std::string_view key, bool any_pose,
                                const ViewRecipe& recipe, double density) {
  const uint64_t seed = object_seed(recipe.seed, key);
  const size_t views = std::max<size_t>(recipe.views, 1);
  std::vector<Cloud> out;
  for (const ScanCondition& sensor : recipe.train_sensors)
    for (size_t v = 0; v < views; ++v)
      out.push_back(sensor_view(mesh, any_pose, full, v, views, seed, sensor, recipe.points, recipe.hpr_radius_factor,
                                density, recipe.filters));
  return out;
}

ObjectViews training_views(const Mesh& mesh, std::string_view key, bool any_pose, const ViewRecipe& recipe,
                           double density) {
  ObjectViews out;
  out.full = full_cloud(mesh, key, recipe);
  out.views = ideal_views(out.full, key, any_pose, recipe);
  if (recipe.views == 0 || recipe.train_sensors.empty()) return out;
  out.first_augmented = out.views.size();
  for (Cloud& c : sensor_views(mesh, out.full, key, any_pose, recipe, density)) out.views.push_back(std::move(c));
  return out;
}

double median_density(std::vector<double> densities) {
  std::erase_if(densities, [](double x) { return !(x > 0); });
  if (densities.empty()) return 0.0;
  std::nth_element(densities.begin(), densities.begin() + std::ptrdiff_t(densities.size() / 2), densities.end());
  return densities[densities.size() / 2];
}

double median_relative_density(const std::vector<Cloud>& views) {
  std::vector<double> d;
  for (const Cloud& c : views) d.push_back(relative_density(c.points));
  return median_density(std::move(d));
}

}  // namespace glimpse
