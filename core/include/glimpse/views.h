// Making the paper's single 2.5D views from full 3D models (sec. 3.4): points from a mesh, the object
// stood upright at real-life size, hidden point removal from a viewpoint, and the top-to-bottom
// exploring sequence of sec. 4. World convention: metres, +z up, the object on the ground (z = 0).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// ---- points from a mesh ----

// Sec. 3.4: "representing the models by the vertices of the meshes".
Cloud mesh_vertices(const Mesh& mesh);

// Area-weighted uniform samples on the triangles: round(area * points_per_m2) points (capped at
// 50M), deterministic for a given seed. Degenerate triangles get none.
Cloud sample_surface(const Mesh& mesh, double points_per_m2, uint64_t seed);

// Total surface area of the triangles, m^2.
double surface_area(const Mesh& mesh);

// ---- orientation, size, placement ----

// The direction that points up in a mesh's own coordinates, a unit vector. As text: a signed axis
// "+z", "-x", "y" (= "+y"), case-insensitive, or three numbers "x y z" (normalised; must not be zero).
Expected<Vec3> parse_up(std::string_view text);
// "+y" for the six axes, else "x y z" with 3 decimals.
std::string up_to_string(const Vec3& up);

// A proper rotation (det +1) that takes `up` to +z: for the six axes a quarter or half turn about
// another axis, otherwise the shortest rotation. Rotating by it stands the object up.
Eigen::Matrix3f upright_rotation(const Vec3& up);
Mesh stand_upright(Mesh mesh, const Vec3& up);

// A rotation drawn uniformly from all 3D rotations (Shoemake 1992), the same for a given seed on every
// machine: the pose of an object that has no natural up (a machine part lying as it fell).
Eigen::Matrix3f random_rotation(uint64_t seed);
Points rotate_points(const Points& points, const Eigen::Matrix3f& rotation);

// A tilt of the up axis by at most `max_deg` degrees in a random direction, uniform over that cap of
// directions (seeded): how far the up of a real scan may be off.
Eigen::Matrix3f random_tilt(uint64_t seed, float max_deg);
// The cloud turned by `rotation` about its centroid, its sensor with it.
Cloud rotate_about_centroid(const Cloud& cloud, const Eigen::Matrix3f& rotation);

// Scales about the origin.
Mesh scale_uniform(Mesh mesh, float factor);
// Uniform scale so the z extent (height) / the largest bounding-box extent equals the target.
// A mesh with zero extent is returned unchanged.
Mesh scale_to_height(Mesh mesh, float height_m);
Mesh scale_to_largest_extent(Mesh mesh, float extent_m);
// Translates so min z = 0 and the bounding-box centre is at x = y = 0.
Mesh place_on_ground(Mesh mesh);
Points place_on_ground(Points points);

// ---- single views ----

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

// ---- the protocol's views of one object (sec. 3.4): the lab, the client and the tests share them ----

// The seed of one object's samples and poses, from (seed, "category/id"): the same wherever and in
// whatever order the object is listed, so the client's views of a folder are the lab's.
uint64_t object_seed(uint64_t seed, std::string_view key);

// An object's full 3D cloud: `points` area-weighted samples (seeded), or its vertices when points is 0
// or the mesh has no area.
Points object_cloud(const Mesh& mesh, size_t points, uint64_t seed);

// View `view` of `views` evenly spaced among the 6 of paper_viewpoints, by hidden point removal. An
// object without a natural up is first turned to a random pose of its own for this view (seeded by
// pose_seed and the view) and put on the ground. `elevation_deg` raises or lowers the ring of viewpoints
// (training views from several heights; the pose is the same at every elevation).
Cloud object_view(const Points& full, size_t view, size_t views, bool any_pose, uint64_t pose_seed,
                  double hpr_radius_factor = 100.0, float elevation_deg = kPaperElevationDeg);

// ---- top-to-bottom exploring sequence (sec. 4) ----

// Point indices by descending z; ties by ascending index; NaN z last.
std::vector<uint32_t> top_down_order(const Points& points);
// The `count` highest points (all if count >= size), in top-down order; the sensor is kept.
Cloud reveal_top_down(const Cloud& cloud, size_t count);
// The indices of the `count` highest points (top_down_order's first `count`), ascending; linear time.
std::vector<uint32_t> highest_points(const Points& points, size_t count);

}  // namespace glimpse
