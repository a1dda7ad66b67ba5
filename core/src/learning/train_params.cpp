// The parameters' derived views and checks.
#include "glimpse/learning/train_params.h"

#include <string>

namespace glimpse {

MethodFeatureParams method_feature_params(const TrainParams& params) {
  MethodFeatureParams p;
  p.local = params.features;
  p.global = params.global;
  p.ush = params.ush;
  p.esf_seed = params.seed;
  p.top_prefix_fraction = params.measure_novelty ? params.novelty_prefix : 0;
  p.top_prefix_min_points = params.novelty_prefix_min_points;
  p.top_prefix_points = params.novelty_prefix_points;
  return p;
}

Status check_codebook_sizes(const TrainParams& p) {
  auto within = [](int v, int lo, int hi, const char* name) -> Status {
    if (v >= lo && v <= hi) return {};
    return invalid_argument(std::string(name) + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                            "], not " + std::to_string(v));
  };
  for (Status s : {within(p.bok_clusters, 2, 100000, "bok_clusters (bok_codebook_size)"),
                   within(p.bog_keypoint_clusters, 2, 40, "bog_keypoint_clusters"),
                   within(p.bog_volume_clusters, 1, 1000, "bog_volume_clusters"),
                   within(p.kgh_clusters, 2, 1000, "kgh_clusters (kgh_keypoint_clusters)"),
                   within(p.kgh_distance_bins, 1, 10000, "kgh_distance_bins")})
    if (!s.ok()) return s;
  return {};
}

}  // namespace glimpse
