// The local features of a cloud, in one state for whole clouds and streams: clean -> density ->
// local surfaces -> normal orientation -> characteristic-scale keypoints -> 12-D descriptors
// (sec. 2.2-2.3, 3.2.1-3.2.4). extract() builds the state in one pass; a ScanFeatures grows it chunk by
// chunk and ends on exactly the state extract() gives the accumulated cloud.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/features/descriptor.h"
#include "glimpse/expected.h"
#include "glimpse/features/keypoints.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/clean.h"
#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

struct FeatureParams {
  float duplicate_tolerance_m = 0;  // 0: drop exact duplicates only
  size_t min_points = 20;           // fewer points after cleaning: an error (a stream: not ready yet)
  bool find_keypoints = true;       // false: stop after the local surfaces (no method needs keypoints)
  SurfaceParams surface;
  KeypointParams keypoints;
  DescriptorParams descriptor;
};

struct FeatureDiagnostics {
  CleanReport clean;
  Density density;                 // every radius used, from one estimate
  float support_radius_m = 0;      // = density.support_radius_m
  size_t valid_surfaces = 0;
  KeypointStats keypoints;
  std::string note;  // why there are no keypoints, when there are none
  size_t radius_changes = 0;  // a stream: how often the snapped radius moved and every surface was redone
  // Wall time per stage: cleaning, the neighbour index and density, local surfaces, keypoints (with the
  // boundary test), descriptors.
  double clean_ms = 0, index_ms = 0, surfaces_ms = 0, keypoints_ms = 0, descriptors_ms = 0;
};

struct FeatureState {
  Cloud cloud;                         // the cleaned cloud all indices refer to
  std::vector<LocalSurface> surfaces;  // one per point of `cloud` (empty when no radius was found)
  std::vector<Keypoint> keypoints;     // in selection order (descending lambda_min)
  std::vector<Descriptor> descriptors;
  FeatureDiagnostics diagnostics;
};

inline constexpr float kMaxCoordinateM = 1e6f;  // 1000 km: beyond any scan, and grid keys stay exact

// What every cloud and chunk must satisfy before its points are used: a finite sensor, no coordinate
// beyond kMaxCoordinateM ("not a scan in metres"). Non-finite points are not an error: cleaning drops
// and counts them. `what` names the cloud in the message ("chunk 3").
Status check_cloud(const Cloud& cloud, std::string_view what = "");

// Errors: empty cloud, no finite point, fewer than min_points after cleaning, a coordinate beyond
// kMaxCoordinateM (invalid argument); cancelled when `cancel` returns true while it works.
// A cloud on which no surface can be fitted (collinear points) or which is flat gives no keypoints
// and a note saying why, not an error.
Expected<FeatureState> extract(const Cloud& cloud, const FeatureParams& params = {}, const CancelFn& cancel = {});

// extract() of a scan fused from several sensor positions: point_sensors names each point's sensor (one
// per point). The points go in per sensor, in the order the sensors first appear, each facing its own
// sensor, as a stream's chunks do (ScanFeatures); with one sensor for every point this is extract() of
// the cloud with it. Errors: extract()'s, and a point_sensors of another length.
bool one_sensor(const std::vector<std::optional<Vec3>>& point_sensors);
Expected<FeatureState> extract_fused(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors,
                                     const FeatureParams& params = {}, const CancelFn& cancel = {});

// The features of a growing scan. Each chunk's points are cleaned by the rule of clean() against
// everything kept before (a re-sent or overlapping chunk changes nothing), the density is re-estimated
// on the accumulated points, and the surfaces of every point whose neighbourhood changed are refitted
// (all of them when the snapped radius moved). Normals face the sensor of the chunk a point came in;
// points without one are oriented by propagation over the whole scan, as extract() does. After any
// sequence of chunks, state() equals extract() of their concatenation (bit for bit).
class ScanFeatures {
 public:
  explicit ScanFeatures(const FeatureParams& params);
  ~ScanFeatures();
  ScanFeatures(ScanFeatures&&) noexcept;
  ScanFeatures& operator=(ScanFeatures&&) noexcept;

  // Adds a chunk (check_cloud errors; nothing is kept then). Returns the number of points kept.
  Expected<size_t> add(const Cloud& chunk, const CancelFn& cancel = {});
  // True once the scan holds min_points points and a density: features are then up to date.
  bool ready() const;
  const FeatureState& state() const;
  size_t points() const;  // kept so far
  // Per point kept (the state's cloud order): the sensor of the chunk it came in, if it had one.
  const std::vector<std::optional<Vec3>>& viewpoints() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glimpse
