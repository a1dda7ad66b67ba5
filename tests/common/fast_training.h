// A Train header whose parameters train the real recogniser in seconds (few clusters, a fixed seed),
// for tests that train over the service.
#pragma once

#include <string>

#include "glimpse/v1/glimpse.pb.h"

namespace glimpse::testing {

inline v1::TrainHeader FastTrainHeader(const std::string& model_name) {
  v1::TrainHeader h;
  h.set_model_name(model_name);
  v1::TrainParameters* p = h.mutable_parameters();
  p->set_bok_codebook_size(6);
  p->set_bog_keypoint_clusters(3);
  p->set_bog_volume_clusters(2);
  p->set_bog_pca_dims(8);
  p->set_kgh_keypoint_clusters(3);
  p->set_seed(11);
  return h;
}

}  // namespace glimpse::testing
