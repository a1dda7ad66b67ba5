// Private: the plane steps of segment_scene (scene_planes.cpp), over the frame's voxel centroids.
#pragma once

#include <cstdint>
#include <numeric>
#include <optional>
#include <vector>

#include "glimpse/geometry/scene.h"

namespace glimpse {

// Voxel labels: 0 = unlabelled, -(k + 1) = the k-th plane removed, c + 1 = the c-th cluster.
using SceneLabels = std::vector<int32_t>;

// Clusters joined into groups (union-find): join(a, b) puts b's group under a's root; relabel numbers the
// groups 1, 2, ... in the order of their roots' labels and returns their count.
class ClusterJoins {
 public:
  explicit ClusterJoins(int32_t clusters) : root_(static_cast<size_t>(clusters)) { std::iota(root_.begin(), root_.end(), 0); }
  int32_t find(int32_t c) {
    while (root_[size_t(c)] != c) c = root_[size_t(c)] = root_[size_t(root_[size_t(c)])];
    return c;
  }
  void join(int32_t a, int32_t b) { root_[size_t(find(b))] = find(a); }
  int32_t relabel(SceneLabels& labels) {
    std::vector<int32_t> renumbered(root_.size(), 0);
    int32_t groups = 0;
    for (int32_t c = 0; c < int32_t(root_.size()); ++c)
      if (find(c) == c) renumbered[size_t(c)] = ++groups;
    for (int32_t& label : labels)
      if (label > 0) label = renumbered[size_t(find(label - 1))];
    return groups;
  }

 private:
  std::vector<int32_t> root_;
};

// A floor or a table top: a plane whose normal (facing the sensor) lies within 20 degrees of +z.
inline bool is_level(const Plane& plane) { return plane.normal.z() >= 0.94f; }
inline float level_height(const Plane& plane) { return -plane.offset / plane.normal.z(); }
// The height of the lowest level plane: the floor's (none without a level plane).
std::optional<float> floor_height(const std::vector<Plane>& planes);

// The large planes, largest first, their broad regions' voxels labelled -(k + 1).
std::vector<Plane> remove_planes(const Points& voxels, const Vec3& sensor, const SceneParams& params, SceneLabels& labels);

// The planes that bound the room or hold objects, the others' voxels unlabelled (0) for clustering: a
// level plane above the floor on which nothing rests (a bare table's top) and, in a +z-up frame, a plane
// that is neither level nor a wall (some of the frame lies behind it: a person's front, an animal's
// flank) are objects' faces. The kept planes' labels are renumbered.
std::vector<Plane> keep_room_and_supports(std::vector<Plane> planes, const Points& voxels, const Vec3& sensor,
                                          const SceneParams& params, SceneLabels& labels);

// Pieces of one object that a nearer object parts (seen either side of it): clusters of at least 20
// voxels whose boxes lie within 50 cm, share half the lower one's height, and the space between whose
// closest voxels lies behind other clusters, are joined; returns the count. For a frame that is +z up.
int32_t join_hidden(const Points& voxels, int32_t clusters, const Vec3& sensor, const SceneParams& params, SceneLabels& labels);

}  // namespace glimpse
