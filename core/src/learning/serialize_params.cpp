// The training parameters of a model as (name, value) pairs (serialize.cpp's format): later versions
// add parameters and still read old models; unknown names are ignored, missing ones keep defaults.
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <type_traits>

#include "glimpse/learning/train_params.h"
#include "learning/serialize_bytes.h"

namespace glimpse {

namespace {

template <class F>
void visit_params(TrainParams& p, F&& f) {
  f("features.duplicate_tolerance_m", p.features.duplicate_tolerance_m);
  f("features.min_points", p.features.min_points);
  f("surface.support_radius_m", p.features.surface.support_radius_m);
  f("surface.support_neighbours", p.features.surface.support_neighbours);
  f("surface.min_neighbours", p.features.surface.min_neighbours);
  f("keypoints.max_characteristic_radius_m", p.features.keypoints.max_characteristic_radius_m);
  f("keypoints.max_radius_supports", p.features.keypoints.max_radius_supports);
  f("keypoints.exclude_boundary", p.features.keypoints.exclude_boundary);
  f("keypoints.boundary_gap_rad", p.features.keypoints.boundary_gap_rad);
  f("keypoints.max_keypoints", p.features.keypoints.max_keypoints);
  f("keypoints.claim_min_supports", p.features.keypoints.claim_min_supports);
  f("keypoints.boundary_band_supports", p.features.keypoints.boundary_band_supports);
  f("keypoints.boundary_radius_supports", p.features.keypoints.boundary_radius_supports);
  f("keypoints.response", p.features.keypoints.response);
  f("descriptor.large_window_supports", p.features.descriptor.large_window_supports);
  f("descriptor.max_pfh_points", p.features.descriptor.max_pfh_points);
  f("descriptor.characteristic_scale_supports", p.features.descriptor.characteristic_scale_supports);
  f("global.normal_radius_m", p.global.normal_radius_m);
  f("global.fill_size_component", p.global.fill_size_component);
  f("ush.max_depth_m", p.ush.max_depth_m);
  f("ush.max_radius_m", p.ush.max_radius_m);
  f("ush.flat_curvedness", p.ush.flat_curvedness);
  f("codebook_explained_variance", p.codebook_explained_variance);
  f("bok_clusters", p.bok_clusters);
  f("bok_soft_words", p.bok_soft_words);
  f("normalise_histograms", p.normalise_histograms);
  f("normalise_up_to_keypoints", p.normalise_up_to_keypoints);
  f("bog_keypoint_clusters", p.bog_keypoint_clusters);
  f("bog_volume_clusters", p.bog_volume_clusters);
  f("bog_pca_dims", p.bog_pca_dims);
  f("kgh_clusters", p.kgh_clusters);
  f("kgh_distance_bins", p.kgh_distance_bins);
  f("decision.kind", p.decision.kind);
  f("decision.centres_per_category", p.decision.centres_per_category);
  f("decision.neighbours", p.decision.neighbours);
  f("decision.pca_explained_variance", p.decision.pca_explained_variance);
  f("decision.max_pca_dims", p.decision.max_pca_dims);
  f("decision.temperature_queries", p.decision.temperature_queries);
  f("fusion_head.c", p.fusion_head.c);
  f("fusion_head.sample_steps", p.fusion_head.sample_steps);
  f("fusion_head.sample_interval", p.fusion_head.sample_interval);
  f("fusion_head_rows_per_category", p.fusion_head_rows_per_category);
  f("kmeans_restarts", p.kmeans_restarts);
  f("calibration_folds", p.calibration_folds);
  f("calibration_queries", p.calibration_queries);
  f("augmented_prefixes", p.augmented_prefixes);
  f("settle_precision", p.settle_precision);
  f("known_acceptance", p.known_acceptance);
  f("novelty_objects", p.novelty_objects);
  f("novelty_prefix", p.novelty_prefix);
  f("novelty_prefix_min_points", p.novelty_prefix_min_points);
  f("novelty_prefix_points", p.novelty_prefix_points);
  f("tilt_deg", p.tilt_deg);
  f("seed", p.seed);
  f("filters.enabled", p.filter_scans);
  f("filters.remove_ground", p.filters.remove_ground);
  f("filters.ground_distance_m", p.filters.ground_distance_m);
  f("filters.max_tilt_deg", p.filters.max_tilt_deg);
  f("filters.ground_band_m", p.filters.ground_band_m);
  f("filters.min_ground_fraction", p.filters.min_ground_fraction);
  f("filters.ground_min_sides", p.filters.ground_min_sides);
  f("filters.min_ground_fill", p.filters.min_ground_fill);
  f("filters.min_ground_extent_m", p.filters.min_ground_extent_m);
  f("filters.remove_outliers", p.filters.remove_outliers);
  f("filters.outlier_radius_spacings", p.filters.outlier_radius_spacings);
  f("filters.outlier_min_neighbours", p.filters.outlier_min_neighbours);
  f("filters.relative_density", p.filters.relative_density);
}

template <class T>
double to_double(const T& v) {
  if constexpr (std::is_enum_v<T>) return static_cast<double>(static_cast<int>(v));
  else return static_cast<double>(v);
}
template <class T, bool = std::is_enum_v<T>>
struct IntegerOf {
  using type = T;
};
template <class T>
struct IntegerOf<T, true> {
  using type = std::underlying_type_t<T>;
};

// False (and v unchanged) when d is not a value of T: NaN, infinite, out of range, or not whole for an
// integer; casting those would be undefined behaviour.
template <class T>
bool from_double(T& v, double d) {
  if (!std::isfinite(d)) return false;
  if constexpr (std::is_same_v<T, bool>) {
    v = d != 0;
  } else if constexpr (std::is_enum_v<T> || std::is_integral_v<T>) {
    using I = typename IntegerOf<T>::type;
    const double upper = std::ldexp(1.0, std::numeric_limits<I>::digits);  // exclusive, exact in binary64
    if (d != std::floor(d) || d < static_cast<double>(std::numeric_limits<I>::lowest()) || d >= upper) return false;
    v = static_cast<T>(static_cast<I>(d));
  } else {
    if (std::abs(d) > static_cast<double>(std::numeric_limits<T>::max())) return false;
    v = static_cast<T>(d);
  }
  return true;
}

}  // namespace

void write_train_params(serial::Writer& w, const TrainParams& params) {
  TrainParams p = params;  // visit_params hands out references to write through
  uint32_t count = 0;
  visit_params(p, [&](const char*, auto&) { ++count; });
  w.u32(count);
  visit_params(p, [&](const char* name, auto& v) {
    w.str(name);
    w.f64(to_double(v));
  });
}

std::map<std::string, double> read_train_params(serial::Reader& r, TrainParams& p) {
  std::map<std::string, double> values;
  const uint32_t count = r.u32("parameter count");
  if (count > 10000) r.fail("too many parameters");
  for (uint32_t i = 0; i < count && !r.failed(); ++i) {
    std::string name = r.str("parameter name");
    values[name] = r.f64("parameter value");
  }
  // Unknown names are ignored and missing ones keep their defaults (older or newer writers).
  visit_params(p, [&](const char* name, auto& v) {
    if (auto it = values.find(name); it != values.end() && !from_double(v, it->second))
      r.fail(std::string("parameter ") + name + " has an impossible value");
  });
  return values;
}

}  // namespace glimpse
