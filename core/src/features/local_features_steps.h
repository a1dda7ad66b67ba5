// Private: the steps extract() and ScanFeatures share (local_features.cpp).
#pragma once

#include <chrono>
#include <optional>
#include <vector>

#include "glimpse/clock.h"
#include "glimpse/features/local_features.h"

namespace glimpse {

void count_valid_surfaces(FeatureState& f);
// Keypoints (sec. 3.2.2) from f.surfaces at f.diagnostics.support_radius_m and their descriptors
// (sec. 2.3). A stream passes what it keeps between calls: the boundary memo and, per point, the
// descriptor already computed there (reset by the caller where a neighbourhood changed).
void find_keypoints_and_descriptors(const NeighbourIndex& index, FeatureState& f, const FeatureParams& params,
                                    BoundaryMemo* memo, std::vector<std::optional<Descriptor>>* cache);

}  // namespace glimpse
