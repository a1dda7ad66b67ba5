// What each method reads of a cloud (sec. 3.1-3.2, 4): its local surfaces and
// keypoints -> the upright histogram, the visible size, VFH, ESF and the keypoint descriptors. One
// implementation for training clouds, classified clouds and streams.
#include "glimpse/features/method_features.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "glimpse/views/exploration.h"

namespace glimpse {

namespace {

// The whole-cloud descriptors `methods` read of these points and their local surfaces (one per point,
// or none): USH, the visible size, VFH over the surfaces' normals, ESF.
Status describe_points(const Cloud& cloud, const std::vector<LocalSurface>& surfaces, const MethodFeatureParams& params,
                       const std::vector<MethodId>& methods, int threads, CloudFeatures& out) {
  if (needs(methods, MethodId::kUSH)) out.ush = upright_histogram(cloud.points, surfaces, params.ush);
  if (needs(methods, MethodId::kSize)) out.size = visible_size(cloud.points);
  if (needs(methods, MethodId::kVFH)) {
    GlobalDescriptorParams gp = params.global;
    gp.threads = threads;
    std::vector<Vec3> normals(cloud.points.size(), Vec3::Zero());
    for (size_t i = 0; i < surfaces.size() && i < normals.size(); ++i)
      if (surfaces[i].valid) normals[i] = surfaces[i].normal;
    auto v = vfh_with_normals(cloud, normals, gp);
    if (!v.ok()) return v.error();
    out.vfh = std::move(*v);
  }
  if (needs(methods, MethodId::kESF)) {
    auto e = esf(cloud, params.esf_seed);
    if (!e.ok()) return e.error();
    out.esf = std::move(*e);
  }
  return {};
}

// The top-down prefix whose novelty joins the cloud's (MethodFeatureParams::top_prefix_fraction): of every k-th point
// (at most top_prefix_points of them), the highest top_prefix_fraction, with their local surfaces as
// fitted on the whole cloud; the keypoints from its lowest point up. None when it would keep fewer than
// top_prefix_min_points, or all of them, or cannot be described; none when top_prefix_fraction is 0.
std::shared_ptr<const CloudFeatures> top_prefix(const FeatureState& f, const MethodFeatureParams& params,
                                                const std::vector<MethodId>& methods, int threads) {
  const size_t n = f.cloud.points.size();
  if (!(params.top_prefix_fraction > 0) || n == 0) return nullptr;
  const size_t cap = std::max<size_t>(1, params.top_prefix_points);
  const size_t step = (n + cap - 1) / cap;
  Points sampled;
  std::vector<size_t> of;
  for (size_t i = 0; i < n; i += step) sampled.push_back(f.cloud.points[i]), of.push_back(i);
  const auto count = static_cast<size_t>(std::lround(params.top_prefix_fraction * static_cast<double>(sampled.size())));
  if (count < std::max<size_t>(params.top_prefix_min_points, 1) || count >= sampled.size()) return nullptr;
  Cloud cloud{{}, f.cloud.sensor, f.cloud.frame};
  std::vector<LocalSurface> surfaces;
  size_t valid = 0;
  float cut = INFINITY;
  for (uint32_t j : highest_points(sampled, count)) {
    const size_t i = of[j];
    cloud.points.push_back(f.cloud.points[i]);
    cut = std::min(cut, f.cloud.points[i].z());
    if (i < f.surfaces.size()) surfaces.push_back(f.surfaces[i]), valid += f.surfaces[i].valid;
  }
  if (valid == 0) return nullptr;
  auto out = std::make_shared<CloudFeatures>();
  out->points = cloud.points.size();
  out->extent_m = bounds(cloud.points).extent().maxCoeff();
  for (size_t k = 0; k < f.keypoints.size(); ++k)
    if (f.keypoints[k].position.z() >= cut) {
      out->positions.push_back(f.keypoints[k].position);
      if (k < f.descriptors.size()) out->descriptors.push_back(f.descriptors[k]);
    }
  if (!describe_points(cloud, surfaces, params, methods, threads, *out).ok()) return nullptr;
  return out;
}

}  // namespace

Expected<CloudFeatures> method_features(const FeatureState& f, const MethodFeatureParams& params,
                                        const std::vector<MethodId>& methods, int threads) {
  // Every method but ESF and size reads the local surfaces (USH, VFH's normals, keypoints): without one
  // there is nothing to judge, and a histogram of nothing would still name a winner.
  const bool surfaces_needed = std::any_of(methods.begin(), methods.end(), [](MethodId m) {
    return m != MethodId::kESF && m != MethodId::kSize && m != MethodId::kFusion;
  });
  if (surfaces_needed && f.diagnostics.valid_surfaces == 0)
    return invalid_argument(f.diagnostics.note.empty() ? "no local surface could be fitted" : f.diagnostics.note);
  CloudFeatures out;
  out.points = f.cloud.points.size();
  out.extent_m = bounds(f.cloud.points).extent().maxCoeff();
  for (const Keypoint& k : f.keypoints) out.positions.push_back(k.position);
  out.descriptors = f.descriptors;
  if (Status s = describe_points(f.cloud, f.surfaces, params, methods, threads, out); !s.ok()) return s.error();
  out.top_prefix = top_prefix(f, params, methods, threads);
  return out;
}

Expected<CloudFeatures> cloud_features(const Cloud& cloud, const MethodFeatureParams& params,
                                       const std::vector<MethodId>& methods, int threads, const CancelFn& cancel) {
  FeatureParams fp = params.local;
  fp.surface.threads = threads;
  fp.find_keypoints = std::any_of(methods.begin(), methods.end(), uses_keypoints);
  auto f = extract(cloud, fp, cancel);
  if (!f.ok()) return f.error();
  if (cancel && cancel()) return cancelled("feature extraction cancelled");
  return method_features(*f, params, methods, threads);
}

}  // namespace glimpse
