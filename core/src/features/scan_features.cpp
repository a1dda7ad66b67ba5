// ScanFeatures: the feature state of a growing scan, kept equal to extract() of the points so far.
// Only neighbourhoods that new points touched are refitted; everything is redone when the density's
// snapped radius moves (rarely: 9 % steps).
#include <algorithm>
#include <chrono>

#include "features/local_features_steps.h"
#include "glimpse/features/local_features.h"
#include "glimpse/geometry/normal_orientation.h"

namespace glimpse {

struct ScanFeatures::Impl {
  explicit Impl(const FeatureParams& p) : params(p), filter(p.duplicate_tolerance_m) {}

  void refit_all();
  void refit_touched(const std::vector<uint32_t>& added);
  void orient();

  FeatureParams params;
  DuplicateFilter filter;
  FeatureState st;
  std::vector<std::optional<Vec3>> viewpoint;  // per point: the sensor of the chunk it came in
  std::optional<Vec3> sensor;
  size_t chunks = 0;
  std::unique_ptr<VoxelIndex> index;           // cells of the support radius
  BoundaryMemo memo;
  std::vector<std::optional<Descriptor>> cache;
  std::vector<uint32_t> epoch;  // scratch marks for "already collected"
  uint32_t epoch_now = 0;
  bool sensorless = false;      // some point came without a sensor: orientation by propagation
};

void ScanFeatures::Impl::refit_all() {
  const float r = st.diagnostics.support_radius_m;
  index = std::make_unique<VoxelIndex>(r);
  for (const Vec3& p : st.cloud.points) index->add(p);
  const size_t n = st.cloud.points.size();
  st.surfaces.assign(n, {});
  std::vector<Neighbour> scratch;
  for (uint32_t i = 0; i < n; ++i)
    st.surfaces[i] = local_surface(*index, i, r, viewpoint[i], params.surface.min_neighbours, scratch);
  memo = {};
  cache.assign(n, std::nullopt);
}

void ScanFeatures::Impl::refit_touched(const std::vector<uint32_t>& added) {
  const float r = st.diagnostics.support_radius_m;
  const size_t n = st.cloud.points.size();
  st.surfaces.resize(n);
  cache.resize(n);
  epoch.resize(n, 0);
  ++epoch_now;
  // Every point within r of a new point has a new neighbourhood.
  std::vector<uint32_t> touched;
  std::vector<Neighbour> near;
  for (uint32_t i : added) {
    index->radius_any_order(st.cloud.points[i], r, near);  // sorted below
    for (const Neighbour& q : near)
      if (epoch[q.index] != epoch_now) epoch[q.index] = epoch_now, touched.push_back(q.index);
  }
  std::sort(touched.begin(), touched.end());
  if (params.keypoints.exclude_boundary) {
    memo.boundary.resize(n, -1);
    memo.touches_boundary.resize(n, -1);
  }
  for (uint32_t i : touched) {
    st.surfaces[i] = local_surface(*index, i, r, viewpoint[i], params.surface.min_neighbours, near);
    // Its boundary status may have changed, and so may "touches a boundary" of its neighbours.
    if (params.keypoints.exclude_boundary) {
      // Boundary status reads a point's normal and its neighbours within the boundary radius B: i's
      // changed, and, when B > r, so may every point within B of i (an added point is among the touched).
      // "Touches a boundary" reads the boundary status within the band: reset within B + band.
      const KeypointParams& kp = params.keypoints;
      const float boundary_reach = kp.boundary_radius_supports > 1 ? kp.boundary_radius_supports * r : 0.f;
      memo.boundary[i] = -1;
      if (boundary_reach > 0) {
        index->radius_any_order(st.cloud.points[i], boundary_reach, near);
        for (const Neighbour& q : near) memo.boundary[q.index] = -1;
      }
      const float touch_reach = boundary_reach + kp.boundary_band_supports * r;
      if (touch_reach > 0) {
        if (boundary_reach > 0 || touch_reach != r) index->radius_any_order(st.cloud.points[i], touch_reach, near);
        for (const Neighbour& q : near) memo.touches_boundary[q.index] = -1;
      } else {
        memo.touches_boundary[i] = -1;
      }
    }
  }
  // Descriptors read normals within their neighbourhood (whose surfaces read r farther) and the large
  // window around the keypoint.
  const float reach = descriptor_reach(r, params.descriptor) + r;
  for (uint32_t i : added) {
    index->radius_any_order(st.cloud.points[i], reach, near);  // resets: any order
    for (const Neighbour& q : near) cache[q.index].reset();
  }
}

void ScanFeatures::Impl::orient() {
  if (!sensorless) return;
  // Propagation over the whole scan, as extract() orients a cloud without a sensor; its result does not
  // depend on the signs the normals had, but a normal it turns changes the descriptors around it.
  std::vector<float> before(st.surfaces.size());
  for (size_t i = 0; i < st.surfaces.size(); ++i) before[i] = st.surfaces[i].normal.x() + 2 * st.surfaces[i].normal.y();
  orient_normals_propagated(*index, st.surfaces);
  for (size_t i = 0; i < st.surfaces.size(); ++i)
    if (before[i] != st.surfaces[i].normal.x() + 2 * st.surfaces[i].normal.y()) {
      std::fill(cache.begin(), cache.end(), std::nullopt);
      return;
    }
}

ScanFeatures::ScanFeatures(const FeatureParams& params) : impl_(std::make_unique<Impl>(params)) {}
ScanFeatures::~ScanFeatures() = default;
ScanFeatures::ScanFeatures(ScanFeatures&&) noexcept = default;
ScanFeatures& ScanFeatures::operator=(ScanFeatures&&) noexcept = default;

bool ScanFeatures::ready() const { return impl_->index != nullptr; }
const FeatureState& ScanFeatures::state() const { return impl_->st; }
size_t ScanFeatures::points() const { return impl_->st.cloud.points.size(); }
const std::vector<std::optional<Vec3>>& ScanFeatures::viewpoints() const { return impl_->viewpoint; }

Expected<size_t> ScanFeatures::add(const Cloud& chunk, const CancelFn& cancel) {
  Impl& m = *impl_;
  if (Status s = check_cloud(chunk, "the chunk"); !s.ok()) return s.error();
  FeatureState& st = m.st;
  FeatureDiagnostics& diag = st.diagnostics;
  st.cloud.frame = joined_frame(st.cloud, chunk, m.chunks++ == 0);
  if (chunk.sensor) m.sensor = chunk.sensor;
  auto t0 = std::chrono::steady_clock::now();
  std::vector<uint32_t> added;
  for (const Vec3& p : chunk.points) {
    ++diag.clean.input;
    if (!p.allFinite()) {
      ++diag.clean.non_finite;
      continue;
    }
    if (!m.filter.keep(p)) {
      ++diag.clean.duplicates;
      continue;
    }
    added.push_back(static_cast<uint32_t>(st.cloud.points.size()));
    st.cloud.points.push_back(p);
    m.viewpoint.push_back(chunk.sensor);
    m.sensorless = m.sensorless || !chunk.sensor;
  }
  diag.clean.kept = st.cloud.points.size();
  st.cloud.sensor = m.sensor;
  diag.clean_ms += ms_since(t0);
  if (added.empty() || st.cloud.points.size() < m.params.min_points) return added.size();

  // The density of everything so far, estimated as extract() estimates it for the same points.
  t0 = std::chrono::steady_clock::now();
  Density density;
  if (m.index) {
    for (uint32_t i : added) m.index->add(st.cloud.points[i]);
    density = estimate_density(*m.index, m.params.surface.support_radius_m, m.params.surface.support_neighbours);
  } else {
    density = estimate_density(*first_guess_index(st.cloud.points),
                               m.params.surface.support_radius_m, m.params.surface.support_neighbours);
  }
  diag.index_ms += ms_since(t0);
  if (!(density.support_radius_m > 0)) return added.size();  // every point coincides so far
  t0 = std::chrono::steady_clock::now();
  const bool moved = !m.index || density.support_radius_m != diag.support_radius_m;
  diag.density = density;
  if (moved) {
    diag.radius_changes += m.index != nullptr;
    diag.support_radius_m = density.support_radius_m;
    m.refit_all();
  } else {
    m.refit_touched(added);  // the new points are in the index already: the density needed them
  }
  m.orient();
  count_valid_surfaces(st);
  diag.surfaces_ms += ms_since(t0);
  if (cancel && cancel()) return cancelled("feature extraction cancelled");
  if (m.params.find_keypoints && diag.valid_surfaces > 0)
    find_keypoints_and_descriptors(*m.index, st, m.params, m.params.keypoints.exclude_boundary ? &m.memo : nullptr,
                                   &m.cache);
  return added.size();
}

bool one_sensor(const std::vector<std::optional<Vec3>>& point_sensors) {
  return std::all_of(point_sensors.begin(), point_sensors.end(),
                     [&](const std::optional<Vec3>& s) { return s == point_sensors.front(); });
}

Expected<FeatureState> extract_fused(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors,
                                     const FeatureParams& params, const CancelFn& cancel) {
  if (point_sensors.size() != cloud.points.size())
    return invalid_argument("a fused scan needs one sensor per point (" + std::to_string(point_sensors.size()) +
                            " for " + std::to_string(cloud.points.size()) + " points)");
  if (one_sensor(point_sensors)) {
    Cloud one = cloud;
    if (!point_sensors.empty()) one.sensor = point_sensors.front();
    return extract(one, params, cancel);
  }
  std::vector<Cloud> groups;
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    auto g = std::find_if(groups.begin(), groups.end(), [&](const Cloud& c) { return c.sensor == point_sensors[i]; });
    if (g == groups.end()) {
      g = groups.insert(groups.end(), Cloud{{}, point_sensors[i], {}});
      if (point_sensors[i] == cloud.sensor) g->frame = cloud.frame;  // the cloud's own view keeps its frame
    }
    g->points.push_back(cloud.points[i]);
  }
  ScanFeatures scan(params);
  for (const Cloud& group : groups)
    if (auto kept = scan.add(group, cancel); !kept.ok()) return kept.error();
  if (!scan.ready())
    return invalid_argument("too few usable points: " + std::to_string(scan.points()) + " after cleaning, at least " +
                            std::to_string(params.min_points) + " needed");
  FeatureState state = scan.state();
  state.cloud.sensor = cloud.sensor ? cloud.sensor : state.cloud.sensor;
  return state;
}

}  // namespace glimpse
