// Boundaries of 2.5D views (sec. 3.2.2): points at the edge of what the sensor saw, whose
// neighbourhood is partly unknown, so they and their neighbours give no keypoints.
#pragma once

#include <cstdint>
#include <vector>

#include "glimpse/geometry/neighbourhoods.h"

namespace glimpse {

// A point is on the boundary when the neighbours projected onto its tangent plane leave an angular
// gap larger than `max_gap_rad` around it (as PCL's BoundaryEstimation).
bool is_boundary_point(const NeighbourIndex& tree, uint32_t index, const Vec3& normal, float r,
                       float max_gap_rad, std::vector<Neighbour>& scratch);

}  // namespace glimpse
