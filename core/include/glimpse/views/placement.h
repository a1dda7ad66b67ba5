// Orientation, size and placement of an object: stood upright (+z), at real-life size, on the ground
// (z = 0), and the random poses and tilts of objects and scans. World convention: metres, +z up.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

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

}  // namespace glimpse
