// The paper's single 2.5D views (sec. 3.4): hidden point removal from the six viewpoints around an
// object, and view k of one object of the protocol.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "glimpse/cloud.h"

namespace glimpse {

// Hidden point removal, Katz, Tal & Basri 2007 ("Direct visibility of point sets"): spherical flip
// of the points about the camera with radius R = radius_factor * (largest camera-point distance),
// then the points whose flipped image is a vertex of the convex hull of (flipped points + camera).
// Returns the visible points in input order, with sensor = camera. Non-finite points and points at
// the camera are never visible. Fewer than 4 usable points: all of them are returned (too few to
// decide). If qhull fails even with joggled input ('QJ'), all usable points are returned.
// Thread-safe (a qhull context per call) and silent (qhull's messages go to /dev/null).
// Useful radius_factor range is about 10..1000: smaller keeps fewer points near silhouettes, larger
// drowns the flipped points in qhull round-off (at 1e4 nearly every point comes back "visible").
// About 15 ms for 10k points, 0.25 s for 100k (tests/bench/bench_views.cpp, one core).
Cloud hidden_point_removal(const Points& points, const Vec3& camera, double radius_factor = 100.0);

// Same, returning the indices of the visible points (ascending).
std::vector<uint32_t> hidden_point_removal_indices(const Points& points, const Vec3& camera,
                                                   double radius_factor = 100.0);

// Sec. 3.4: 6 viewpoints per object: azimuth 0, 60, ..., 300 deg about +z, elevation 30 deg above
// the horizon, at 3x the bounding-sphere radius (largest distance from the centroid) from the
// centroid. Empty input gives no viewpoints. Another elevation gives the same ring higher or lower.
inline constexpr float kPaperElevationDeg = 30.f;
std::vector<Vec3> paper_viewpoints(const Points& points, float elevation_deg = kPaperElevationDeg);

// View `view` of `views` evenly spaced among the 6 of paper_viewpoints, by hidden point removal. An
// object without a natural up is first turned to a random pose of its own for this view (seeded by
// pose_seed and the view) and put on the ground. `elevation_deg` raises or lowers the ring of viewpoints
// (training views from several heights; the pose is the same at every elevation).
Cloud object_view(const Points& full, size_t view, size_t views, bool any_pose, uint64_t pose_seed,
                  double hpr_radius_factor = 100.0, float elevation_deg = kPaperElevationDeg);

}  // namespace glimpse
