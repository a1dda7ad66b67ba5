// segment_scene's join of one object's pieces that a nearer object parts (scene_steps.h): a chair behind
// a table's leg, an animal behind a person are seen as two pieces either side of what stands before them.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "glimpse/spatial_hash.h"
#include "scene_steps.h"

namespace glimpse {
namespace {

// What the sensor sees first in each direction: the frame's voxels binned by azimuth and elevation from
// the sensor in kCellRad cells, each cell keeping its nearest voxel's range and label.
class RangeImage {
 public:
  static constexpr float kCellRad = 0.006f;  // 0.34 degrees: 1 cm at 1.7 m, no holes between 1 cm voxels

  RangeImage(const Points& voxels, const SceneLabels& labels, const Vec3& sensor) : sensor_(sensor) {
    cells_.reserve(voxels.size());
    for (size_t i = 0; i < voxels.size(); ++i) {
      const float range = (voxels[i] - sensor_).norm();
      auto [it, fresh] = cells_.try_emplace(key(voxels[i]), Nearest{range, labels[i]});
      if (!fresh && range < it->second.range) it->second = Nearest{range, labels[i]};
    }
  }

  // The cluster label of what hides p from the sensor (something at least margin_m nearer along its
  // ray), 0 when nothing does or the nearest thing is a plane; -1 when the sensor saw nothing that way.
  int32_t hidden_by(const Vec3& p, float margin_m) const {
    const auto it = cells_.find(key(p));
    if (it == cells_.end()) return -1;
    return it->second.range < (p - sensor_).norm() - margin_m ? std::max(0, it->second.label) : 0;
  }

 private:
  struct Nearest {
    float range;
    int32_t label;
  };
  CellKey key(const Vec3& p) const {
    const Vec3 d = (p - sensor_).normalized();
    return {grid_cell<int64_t>(std::atan2(d.y(), d.x()), kCellRad), grid_cell<int64_t>(std::asin(d.z()), kCellRad), 0};
  }
  Vec3 sensor_;
  std::unordered_map<CellKey, Nearest, CellKeyHash> cells_;
};

// Every step-th of `members`, at most max_points.
std::vector<uint32_t> thinned(const std::vector<uint32_t>& members, size_t max_points) {
  const size_t step = std::max<size_t>(1, (members.size() + max_points - 1) / max_points);
  std::vector<uint32_t> out;
  for (size_t k = 0; k < members.size(); k += step) out.push_back(members[k]);
  return out;
}

// The closest pair of voxels between two clusters (each thinned to at most kMaxPoints).
std::pair<Vec3, Vec3> closest_pair(const Points& voxels, const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  constexpr size_t kMaxPoints = 1500;
  const std::vector<uint32_t> ta = thinned(a, kMaxPoints), tb = thinned(b, kMaxPoints);
  float best = std::numeric_limits<float>::infinity();
  std::pair<Vec3, Vec3> pair{voxels[ta.front()], voxels[tb.front()]};
  for (uint32_t i : ta)
    for (uint32_t j : tb)
      if (const float d = (voxels[i] - voxels[j]).squaredNorm(); d < best) best = d, pair = {voxels[i], voxels[j]};
  return pair;
}

// Whether the space between a and b, sampled every 2 cm, lies behind clusters, most of it behind others
// than a and b (a piece behind its own object's near part may as well be another object behind it).
bool gap_hidden(const RangeImage& image, const Vec3& a, const Vec3& b, int32_t label_a, int32_t label_b, float margin_m) {
  constexpr float kStep = 0.02f;
  const int samples = std::max(1, int((b - a).norm() / kStep) - 1);
  int by_others = 0;
  for (int k = 1; k <= samples; ++k) {
    const int32_t by = image.hidden_by(a + (b - a) * (float(k) / float(samples + 1)), margin_m);
    if (by <= 0) return false;
    by_others += by != label_a && by != label_b;
  }
  return 2 * by_others >= samples;
}

struct ClusterBox {
  Bounds box{Vec3::Constant(INFINITY), Vec3::Constant(-INFINITY)};
  std::vector<uint32_t> members;
};

}  // namespace

int32_t join_hidden(const Points& voxels, int32_t clusters, const Vec3& sensor, const SceneParams& params, SceneLabels& labels) {
  constexpr size_t kMinVoxels = 20;
  constexpr float kMaxGap = 0.5f, kMinHeightShare = 0.5f;  // chosen on scenes of SHREC 2007 meshes (docs/results.md)
  std::vector<ClusterBox> c(static_cast<size_t>(clusters));
  for (uint32_t i = 0; i < voxels.size(); ++i)
    if (labels[i] > 0) {
      ClusterBox& k = c[size_t(labels[i] - 1)];
      k.box.min = k.box.min.cwiseMin(voxels[i]), k.box.max = k.box.max.cwiseMax(voxels[i]);
      k.members.push_back(i);
    }
  std::optional<RangeImage> image;  // made for the first pair that needs it
  ClusterJoins joins(clusters);
  for (int32_t a = 0; a < clusters; ++a)
    for (int32_t b = a + 1; b < clusters && c[size_t(a)].members.size() >= kMinVoxels; ++b) {
      const Bounds &p = c[size_t(a)].box, &q = c[size_t(b)].box;
      if (c[size_t(b)].members.size() < kMinVoxels || joins.find(a) == joins.find(b)) continue;
      const float gap = (p.min - q.max).cwiseMax(q.min - p.max).cwiseMax(0.f).norm();
      const float shared = std::min(p.max.z(), q.max.z()) - std::max(p.min.z(), q.min.z());
      if (gap > kMaxGap || shared < kMinHeightShare * std::min(p.max.z() - p.min.z(), q.max.z() - q.min.z())) continue;
      const auto [pa, pb] = closest_pair(voxels, c[size_t(a)].members, c[size_t(b)].members);
      if (!image) image.emplace(voxels, labels, sensor);
      if (gap_hidden(*image, pa, pb, a + 1, b + 1, params.cluster_tolerance_m)) joins.join(a, b);
    }
  return joins.relabel(labels);
}

}  // namespace glimpse
