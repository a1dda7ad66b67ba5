// The top-to-bottom exploring sequence of sec. 4: a view revealed from its highest point down, and the
// stages at which the protocol decides (the whole view, a top prefix holding k keypoints or a fraction of
// the object's full cloud).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "glimpse/cloud.h"

namespace glimpse {

// Point indices by descending z; ties by ascending index; NaN z last.
std::vector<uint32_t> top_down_order(const Points& points);
// The `count` highest points (all if count >= size), in top-down order; the sensor is kept.
Cloud reveal_top_down(const Cloud& cloud, size_t count);
// The indices of the `count` highest points (top_down_order's first `count`), ascending; linear time.
std::vector<uint32_t> highest_points(const Points& points, size_t count);

enum class StageKind : uint8_t {
  kFull,       // the whole single view
  kKeypoints,  // the top prefix in which `value` keypoints are visible (paper: 10, 25, 55)
  kFraction,   // the top prefix holding `value` x the FULL 3D cloud's point count (0.10, 0.20)
};

struct Stage {
  StageKind kind = StageKind::kFull;
  double value = 0;
  bool operator==(const Stage&) const = default;
};

// "full", "10kp", "10%".
std::string stage_name(const Stage& stage);
// full, 10kp, 25kp, 55kp, 10%, 20%.
std::vector<Stage> paper_stages();

// Prefix length (points, top-down) in which the k highest of the view's keypoints are visible: all
// points at or above (k-th highest keypoint height - margin_m). The keypoints are those found on the
// FULL view; re-extracting on the prefix finds nearly the same ones above the cut (selection is greedy
// by curvature, so a keypoint can change when a stronger one below the cut disappears) and none within
// the boundary margin of the cut, which is why `margin_m` is about a support radius. Fewer than k
// keypoints: the whole view.
size_t keypoint_prefix(const Points& view, std::vector<float> keypoint_heights, size_t k, float margin_m);
// round(fraction x full_cloud_points), at most the view's size.
size_t fraction_prefix(size_t view_points, size_t full_cloud_points, double fraction);
// Keypoint counts at which the exploration's decisions are sampled: 1, step, 2 step, ... up to
// max_keypoints (included). step 1 gives the paper's every-keypoint sequence.
std::vector<size_t> exploration_grid(size_t max_keypoints, size_t step);

}  // namespace glimpse
