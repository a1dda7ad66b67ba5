// One entry point for the local features of a cloud: clean -> neighbourhoods -> local surfaces ->
// characteristic-scale keypoints -> 12-D descriptors (sec. 2.2-2.3, 3.2.1-3.2.4).
#pragma once

#include <string>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/descriptor.h"
#include "glimpse/expected.h"
#include "glimpse/neighbourhoods.h"
#include "glimpse/preprocess.h"
#include "glimpse/surface_fit.h"
#include "glimpse/keypoints.h"

namespace glimpse {

struct FeatureParams {
  float duplicate_tolerance_m = 0;  // 0: drop exact duplicates only
  size_t min_points = 20;           // fewer points after cleaning: an error
  bool find_keypoints = true;       // false: stop after the local surfaces (no method needs keypoints)
  SurfaceParams surface;
  KeypointParams keypoints;
  DescriptorParams descriptor;
};

struct FeatureDiagnostics {
  CleanReport clean;
  float support_radius_m = 0;
  size_t valid_surfaces = 0;
  KeypointStats keypoints;
  std::string note;  // why there are no keypoints, when there are none
  // Wall time per stage: cleaning, the neighbour index and support radius, local surfaces,
  // keypoints (with the boundary test), descriptors.
  double clean_ms = 0, index_ms = 0, surfaces_ms = 0, keypoints_ms = 0, descriptors_ms = 0;
};

struct Features {
  Cloud cloud;                       // the cleaned cloud all indices refer to
  std::vector<Keypoint> keypoints;   // in selection order (descending lambda_min)
  std::vector<Descriptor> descriptors;
  std::vector<LocalSurface> surfaces;  // one per point of `cloud` (empty when no radius was found)
  FeatureDiagnostics diagnostics;
};

// Errors: empty cloud, no finite point, fewer than min_points after cleaning, a coordinate beyond
// kMaxCoordinateM (invalid argument); cancelled when `cancel` returns true while it works.
// A cloud on which no surface can be fitted (collinear points) or which is flat gives no keypoints
// and a note saying why, not an error.
inline constexpr float kMaxCoordinateM = 1e6f;  // 1000 km: beyond any scan, and grid keys stay exact
Expected<Features> extract(const Cloud& cloud, const FeatureParams& params = {}, const CancelFn& cancel = {});

}  // namespace glimpse
