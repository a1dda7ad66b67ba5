// The feature state of a cloud (local_features.h): validation, cleaning, density, surfaces, orientation,
// keypoints and descriptors in one place, for extract() and for a growing scan (scan_features.cpp).
#include "glimpse/features/local_features.h"

#include <chrono>
#include <string>

#include "features/local_features_steps.h"
#include "glimpse/geometry/normal_orientation.h"
#include "glimpse/threads.h"

namespace glimpse {

Status check_cloud(const Cloud& cloud, std::string_view what) {
  const std::string of = what.empty() ? "" : " of " + std::string(what);
  if (cloud.sensor && !cloud.sensor->allFinite()) return invalid_argument("the sensor position" + of + " is not finite");
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Vec3& p = cloud.points[i];
    if (p.allFinite() && p.cwiseAbs().maxCoeff() > kMaxCoordinateM)
      return invalid_argument("point " + std::to_string(i) + of + " lies beyond " + std::to_string(int(kMaxCoordinateM)) +
                              " m of the origin: not a scan in metres");
  }
  return {};
}

void count_valid_surfaces(FeatureState& f) {
  f.diagnostics.valid_surfaces = 0;
  for (const LocalSurface& s : f.surfaces) f.diagnostics.valid_surfaces += s.valid;
}

void find_keypoints_and_descriptors(const NeighbourIndex& index, FeatureState& f, const FeatureParams& params,
                                    BoundaryMemo* memo, std::vector<std::optional<Descriptor>>* cache) {
  FeatureDiagnostics& diag = f.diagnostics;
  const float r = diag.support_radius_m;
  auto t0 = std::chrono::steady_clock::now();
  f.keypoints = characteristic_scale_keypoints(index, f.surfaces, r, params.keypoints, &diag.keypoints, memo);
  diag.keypoints_ms += ms_since(t0);
  f.descriptors.assign(f.keypoints.size(), Descriptor::Zero());
  diag.note.clear();
  if (f.keypoints.empty()) {
    diag.note = diag.keypoints.candidates == 0
                    ? "flat: no point is curved enough (rho1 above the maximum characteristic radius)"
                    : "every curved point touches the boundary of the view";
    return;
  }
  t0 = std::chrono::steady_clock::now();
  if (cache) cache->resize(f.cloud.points.size());
  const int threads = resolve_threads(params.surface.threads);
#pragma omp parallel num_threads(threads)
  {
    std::vector<Neighbour> scratch;
#pragma omp for schedule(dynamic, 4)
    for (int64_t i = 0; i < static_cast<int64_t>(f.keypoints.size()); ++i) {
      const Keypoint& k = f.keypoints[static_cast<size_t>(i)];
      if (cache && (*cache)[k.index]) {
        f.descriptors[static_cast<size_t>(i)] = *(*cache)[k.index];
        continue;
      }
      f.descriptors[static_cast<size_t>(i)] = local_descriptor(index, f.surfaces, k, r, params.descriptor, scratch);
      if (cache) (*cache)[k.index] = f.descriptors[static_cast<size_t>(i)];  // each keypoint its own slot
    }
  }
  diag.descriptors_ms += ms_since(t0);
}

Expected<FeatureState> extract(const Cloud& input, const FeatureParams& params, const CancelFn& cancel) {
  if (input.points.empty()) return invalid_argument("the cloud is empty");
  if (Status s = check_cloud(input); !s.ok()) return s.error();
  auto stopped = [&] { return cancel && cancel(); };
  FeatureState f;
  FeatureDiagnostics& diag = f.diagnostics;
  auto t0 = std::chrono::steady_clock::now();
  f.cloud = clean(input, params.duplicate_tolerance_m, &diag.clean);
  diag.clean_ms = ms_since(t0);
  if (f.cloud.points.empty())
    return invalid_argument("the cloud has no finite point (" + std::to_string(diag.clean.non_finite) +
                            " NaN/Inf points)");
  if (f.cloud.points.size() < params.min_points)
    return invalid_argument("the cloud has " + std::to_string(f.cloud.points.size()) + " usable point" +
                            (f.cloud.points.size() == 1 ? "" : "s") + " after cleaning; at least " +
                            std::to_string(params.min_points) + " are needed");

  t0 = std::chrono::steady_clock::now();
  // Cells of a first guess answer the density's queries; cells of r then answer every later one (about
  // twice as fast as a kd-tree, the same neighbourhoods to the bit). Where the points spread too wide
  // for either grid's cells (not a few stray ones: border cells hold those), a kd-tree answers instead.
  diag.density = estimate_density(*first_guess_index(f.cloud.points),
                                  params.surface.support_radius_m, params.surface.support_neighbours);
  diag.support_radius_m = diag.density.support_radius_m;
  diag.index_ms = ms_since(t0);
  if (!(diag.support_radius_m > 0)) {
    diag.note = "no support radius: every point coincides with another";
    return f;
  }
  t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<NeighbourIndex> index_of_r = fixed_cloud_index(f.cloud.points, diag.support_radius_m);
  const NeighbourIndex& index = *index_of_r;
  f.surfaces = local_surfaces(index, diag.support_radius_m, f.cloud.sensor, params.surface, cancel);
  if (stopped()) return cancelled("feature extraction cancelled");
  count_valid_surfaces(f);
  diag.surfaces_ms = ms_since(t0);
  if (diag.valid_surfaces == 0) {
    diag.note = "no local surface could be fitted (too few neighbours within r, or collinear points)";
    return f;
  }
  if (stopped()) return cancelled("feature extraction cancelled");
  if (params.find_keypoints) find_keypoints_and_descriptors(index, f, params, nullptr, nullptr);
  return f;
}

}  // namespace glimpse
