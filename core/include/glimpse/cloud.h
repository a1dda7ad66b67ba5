// The plain data every stage passes along: a point cloud (with the sensor position when known) and a
// triangle mesh. Units are metres throughout.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace glimpse {

using Vec3 = Eigen::Vector3f;
using Points = std::vector<Vec3>;

struct Cloud {
  Points points;
  std::optional<Vec3> sensor;  // viewpoint of a single 2.5D view; absent for fused or full 3D clouds
};

struct Mesh {
  Points vertices;
  std::vector<Eigen::Vector3i> faces;  // triangles, indices into vertices
};

// Axis-aligned bounds of a point set (min, max); both zero for an empty set.
struct Bounds {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  Vec3 extent() const { return max - min; }
  Vec3 centre() const { return 0.5f * (min + max); }
};
Bounds bounds(const Points& points);

}  // namespace glimpse
