// What the global descriptors (VFH in global_descriptors.cpp, ESF in global_descriptors_esf.cpp) share.
#pragma once

#include <Eigen/Core>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse::global_internal {

// A clear error naming `who` for a cloud no global descriptor can take (too few points, NaN or Inf,
// all points coinciding).
Status validate(const Cloud& cloud, const char* who);

Eigen::Vector3d centroid(const Points& points);

}  // namespace glimpse::global_internal
