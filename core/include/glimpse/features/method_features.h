// What each method reads of a cloud (sec. 3.1-3.2, 4): the keypoints and their 12-D descriptors (BoK, BoG,
// KGH), the upright shape histogram, the visible size, VFH over the local surfaces' normals and ESF. One
// implementation for training clouds, classified clouds and streams.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/features/descriptor.h"
#include "glimpse/features/global_descriptors.h"
#include "glimpse/features/local_features.h"
#include "glimpse/features/methods.h"
#include "glimpse/features/upright_histogram.h"

namespace glimpse {

// How the methods' features are computed (a model's TrainParams hold them: method_feature_params).
struct MethodFeatureParams {
  FeatureParams local;             // the local features every method starts from (extract)
  GlobalDescriptorParams global;   // VFH
  UprightHistogramParams ush;
  uint64_t esf_seed = 42;          // ESF's random draws
  // The top-down prefix described beside the cloud (CloudFeatures::top_prefix), whose novelty joins the
  // cloud's: this fraction of the cloud's points, from every k-th point (at most top_prefix_points), when
  // it keeps at least top_prefix_min_points. 0: none.
  double top_prefix_fraction = 0;
  size_t top_prefix_min_points = 300;
  size_t top_prefix_points = 2000;
};

// What the methods of a model need from one cloud.
struct CloudFeatures {
  std::vector<Vec3> positions;           // keypoint positions
  std::vector<Descriptor> descriptors;   // their 12-D descriptors
  std::optional<Eigen::VectorXf> vfh;
  std::optional<Eigen::VectorXf> esf;
  std::optional<Eigen::VectorXf> ush;
  std::optional<Eigen::VectorXf> size;  // visible_size: the size-only baseline
  size_t points = 0;
  float extent_m = 0;  // the largest bounding-box extent of the cleaned cloud
  // The same methods' features of the cloud's top-down prefix (MethodFeatureParams::top_prefix_fraction);
  // none when off or the prefix is too small.
  std::shared_ptr<const CloudFeatures> top_prefix;
};

// What the given methods need of a feature state: keypoint positions and descriptors, and the
// whole-cloud descriptors (USH and size from the points and surfaces, VFH over the surfaces' normals,
// ESF); with a top prefix, the same of it. Shared by whole clouds (cloud_features) and streams.
// Errors: no local surface where a method reads them, a global descriptor's error.
Expected<CloudFeatures> method_features(const FeatureState& state, const MethodFeatureParams& params,
                                        const std::vector<MethodId>& methods, int threads);

// extract() + method_features; keypoints only when one of the methods needs them.
Expected<CloudFeatures> cloud_features(const Cloud& cloud, const MethodFeatureParams& params,
                                       const std::vector<MethodId>& methods, int threads,
                                       const CancelFn& cancel = {});

}  // namespace glimpse
