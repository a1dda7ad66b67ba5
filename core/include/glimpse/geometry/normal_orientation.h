// Orienting normals (sec. 3.2.4): towards the camera when the viewpoint is known, else by normal
// orientation propagation.
#pragma once

#include <vector>

#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

// Normal orientation propagation (Hoppe et al. 1992): a minimum spanning tree over the k-nearest-
// neighbour graph weighted by 1 - |n_i . n_j| flips normals to agree with their parent; each connected
// component is then turned outward (away from its centroid). Deterministic and pose-independent.
void orient_normals_propagated(const NeighbourIndex& tree, std::vector<LocalSurface>& surfaces, int k = 8);

}  // namespace glimpse
