// What a model computes for a method.
#include "glimpse/learning/model_internals.h"

namespace glimpse {

std::vector<MethodId> component_methods(const ModelImpl& impl, MethodId method) {
  if (method != MethodId::kFusion) return {method};
  std::vector<MethodId> out;
  for (MethodId m : impl.params.fusion_of)
    if (m != MethodId::kFusion && impl.stages[static_cast<int>(m)]) out.push_back(m);
  return out;
}

MethodFeatureParams feature_params_for(const ModelImpl& impl, MethodId method) {
  MethodFeatureParams p = method_feature_params(impl.params);
  const Calibration& c = novelty_calibration(impl);
  if (c.method != method || c.novelty_scale.empty()) p.top_prefix_fraction = 0;
  return p;
}

}  // namespace glimpse
