// Objects cut by the frame: which edges of a camera's image a single view's points reach. A person seen
// from 0.8 m shows the torso; its top is the frame's edge, not the object's, and its size is what the
// frame lets through. The answer says so, and the size rule does not call such a part too small
// (learning/novelty.h).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "glimpse/cloud.h"

namespace glimpse {

struct FrameCut {
  // The image's edges the object reaches (top: the image's up).
  bool top = false, bottom = false, left = false, right = false;
  bool any() const { return top || bottom || left || right; }
};

struct FrameCutParams {
  // A point is on an edge within this share of the half-field (in the image plane's tangents): 1 % is
  // about 2.4 pixels of a 480-row camera.
  float edge_share = 0.01f;
  // An edge cuts the object when at least this many points lie on it (a lone stray is no cut).
  size_t min_points = 5;
};

// The edges of `cloud.frame` that its points reach, seen from `cloud.sensor`; nothing cut without a
// sensor and a frame, or with a field of view outside (0, 180) degrees.
FrameCut frame_cut(const Cloud& cloud, const FrameCutParams& params = {});

// The image's edges cut, in the order top, bottom, left, right: {"top", "left"}; none when nothing is.
std::vector<std::string> frame_edges(const FrameCut& cut);
// "top, left", or empty.
std::string describe(const FrameCut& cut);

}  // namespace glimpse
