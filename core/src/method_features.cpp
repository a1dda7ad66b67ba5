// The methods by name, and what each method reads of a cloud (sec. 3.1-3.2, 4): its local surfaces and
// keypoints -> the upright histogram, the visible size, VFH, ESF and the keypoint descriptors. One
// implementation for training clouds, classified clouds and streams.
#include <algorithm>
#include <cctype>
#include <string>

#include "glimpse/model.h"
#include "glimpse/train_params.h"
#include "glimpse/upright_histogram.h"
#include "model_impl.h"

namespace glimpse {

const char* method_name(MethodId m) {
  switch (m) {
    case MethodId::kBoK: return "bok";
    case MethodId::kBoG: return "bog";
    case MethodId::kKGH: return "kgh";
    case MethodId::kVFH: return "vfh";
    case MethodId::kESF: return "esf";
    case MethodId::kUSH: return "ush";
    case MethodId::kSize: return "size";
    case MethodId::kFusion: return "fusion";
  }
  return "unknown";
}

Expected<MethodId> parse_method(std::string_view name) {
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (MethodId m : kAllMethods)
    if (lower == method_name(m)) return m;
  return invalid_argument("unknown method '" + std::string(name) + "' (valid: bok, bog, kgh, vfh, esf, ush, size, fusion)");
}

std::vector<MethodId> component_methods(const ModelImpl& impl, MethodId method) {
  if (method != MethodId::kFusion) return {method};
  std::vector<MethodId> out;
  for (MethodId m : impl.params.fusion_of)
    if (m != MethodId::kFusion && impl.stages[static_cast<int>(m)]) out.push_back(m);
  return out;
}

Expected<CloudFeatures> method_features(const FeatureState& f, const TrainParams& params,
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
  if (needs(methods, MethodId::kUSH)) out.ush = upright_histogram(f.cloud.points, f.surfaces, params.ush);
  if (needs(methods, MethodId::kSize)) out.size = visible_size(f.cloud.points);
  if (needs(methods, MethodId::kVFH)) {
    GlobalDescriptorParams gp = params.global;
    gp.threads = threads;
    std::vector<Vec3> normals(f.cloud.points.size(), Vec3::Zero());
    for (size_t i = 0; i < f.surfaces.size() && i < normals.size(); ++i)
      if (f.surfaces[i].valid) normals[i] = f.surfaces[i].normal;
    auto v = vfh_with_normals(f.cloud, normals, gp);
    if (!v.ok()) return v.error();
    out.vfh = std::move(*v);
  }
  if (needs(methods, MethodId::kESF)) {
    auto e = esf(f.cloud, params.seed);
    if (!e.ok()) return e.error();
    out.esf = std::move(*e);
  }
  return out;
}

Expected<CloudFeatures> cloud_features(const Cloud& cloud, const TrainParams& params,
                                       const std::vector<MethodId>& methods, int threads, const CancelFn& cancel) {
  FeatureParams fp = params.features;
  fp.surface.threads = threads;
  fp.find_keypoints = std::any_of(methods.begin(), methods.end(), uses_keypoints);
  auto f = extract(cloud, fp, cancel);
  if (!f.ok()) return f.error();
  if (cancel && cancel()) return cancelled("feature extraction cancelled");
  return method_features(*f, params, methods, threads);
}

}  // namespace glimpse
