// The plain data every stage passes along: a point cloud (with the sensor position when known) and a
// triangle mesh. Units are metres throughout.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace glimpse {

using Vec3 = Eigen::Vector3f;
using Points = std::vector<Vec3>;

// Where a camera's image ends, for a single view from Cloud::sensor: its optical axis and the image's
// up (unit, orthogonal), and its full fields of view. An object that reaches an edge of the image may
// continue past it (geometry/frame_cut.h).
struct CameraFrame {
  Vec3 axis = Vec3::UnitX();
  Vec3 up = Vec3::UnitZ();
  float fov_h_deg = 0, fov_v_deg = 0;
};

inline bool operator==(const CameraFrame& a, const CameraFrame& b) {
  return a.axis == b.axis && a.up == b.up && a.fov_h_deg == b.fov_h_deg && a.fov_v_deg == b.fov_v_deg;
}

struct Cloud {
  Points points;
  std::optional<Vec3> sensor;  // viewpoint of a single 2.5D view; absent for fused or full 3D clouds
  std::optional<CameraFrame> frame;  // the camera's frame round `sensor`; absent: unknown (nothing is cut)
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

// The camera frame of a scan grown by `chunk` (`first`: its first chunk): the chunk's when first, then the
// scan's while every chunk comes from the same sensor through the same frame (one view streamed); none
// once the sensor moves, since one frame cannot say where another position's image ends.
inline std::optional<CameraFrame> joined_frame(const Cloud& scan, const Cloud& chunk, bool first) {
  if (first) return chunk.frame;
  if (chunk.frame != scan.frame || (chunk.sensor && chunk.sensor != scan.sensor)) return std::nullopt;
  return scan.frame;
}

}  // namespace glimpse
