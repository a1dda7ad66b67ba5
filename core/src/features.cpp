#include "glimpse/features.h"

#include <chrono>
#include <string>

#include "parallel.h"

namespace glimpse {

namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

Expected<Features> extract(const Cloud& input, const FeatureParams& params, const CancelFn& cancel) {
  if (input.points.empty()) return invalid_argument("the cloud is empty");
  if (input.sensor && !input.sensor->allFinite()) return invalid_argument("the sensor position is not finite");
  for (size_t i = 0; i < input.points.size(); ++i) {
    const Vec3& p = input.points[i];
    if (p.allFinite() && p.cwiseAbs().maxCoeff() > kMaxCoordinateM)
      return invalid_argument("point " + std::to_string(i) + " lies beyond " + std::to_string(int(kMaxCoordinateM)) +
                              " m of the origin: not a scan in metres");
  }
  auto stopped = [&] { return cancel && cancel(); };
  Features f;
  FeatureDiagnostics& diag = f.diagnostics;
  auto t0 = std::chrono::steady_clock::now();
  f.cloud = clean(input, params.duplicate_tolerance_m, &diag.clean);
  diag.clean_ms = ms_since(t0);
  if (f.cloud.points.empty())
    return invalid_argument("the cloud has no finite point (" + std::to_string(diag.clean.non_finite) +
                            " NaN/Inf points)");
  if (f.cloud.points.size() < params.min_points)
    return invalid_argument("the cloud has " + std::to_string(f.cloud.points.size()) +
                            " usable points after cleaning; at least " + std::to_string(params.min_points) +
                            " are needed");

  t0 = std::chrono::steady_clock::now();
  const KdTree tree(f.cloud.points);
  const float r = support_radius(tree, params.surface);
  diag.support_radius_m = r;
  diag.index_ms = ms_since(t0);
  if (!(r > 0)) {
    diag.note = "no support radius: every point coincides with another";
    return f;
  }
  t0 = std::chrono::steady_clock::now();
  f.surfaces = local_surfaces(tree, r, f.cloud.sensor, params.surface, cancel);
  if (stopped()) return cancelled("feature extraction cancelled");
  const std::vector<LocalSurface>& surfaces = f.surfaces;
  for (const LocalSurface& s : surfaces) diag.valid_surfaces += s.valid;
  diag.surfaces_ms = ms_since(t0);
  if (diag.valid_surfaces == 0) {
    diag.note = "no local surface could be fitted (too few neighbours within r, or collinear points)";
    return f;
  }

  if (stopped()) return cancelled("feature extraction cancelled");
  if (!params.find_keypoints) return f;
  t0 = std::chrono::steady_clock::now();
  f.keypoints = characteristic_scale_keypoints(tree, surfaces, r, params.keypoints, &diag.keypoints);
  diag.keypoints_ms = ms_since(t0);
  if (f.keypoints.empty()) {
    diag.note = diag.keypoints.candidates == 0
                    ? "flat: no point is curved enough (rho1 above the maximum characteristic radius)"
                    : "every curved point touches the boundary of the view";
    return f;
  }

  t0 = std::chrono::steady_clock::now();
  f.descriptors.resize(f.keypoints.size());
  const int threads = resolve_threads(params.surface.threads);
#pragma omp parallel num_threads(threads)
  {
    std::vector<Neighbour> scratch;
#pragma omp for schedule(dynamic, 4)
    for (int64_t i = 0; i < static_cast<int64_t>(f.keypoints.size()); ++i)
      f.descriptors[i] = local_descriptor(tree, surfaces, f.keypoints[i], r, params.descriptor, scratch);
  }
  diag.descriptors_ms = ms_since(t0);
  return f;
}

}  // namespace glimpse
