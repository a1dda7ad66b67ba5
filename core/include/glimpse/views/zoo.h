// A procedural shape zoo for the paper's five categories (sec. 3.4: human, chair, table, angular
// machine part, quadruped), so training, tests and benchmarks run without the SHREC dataset.
//
// Each shape is a union of overlapping primitives (boxes, tapered capsules, ellipsoids, extruded
// outlines with holes such as gears and nuts, tori) with proportions, variant (e.g. four legs vs
// pedestal) and pose drawn from the seed; it stands upright (+z), on the ground (min z = 0), centred
// in x, y, at a real-life size drawn from default_category_sizes() (dataset.h), with a random yaw.
// Primitives are tessellated evenly, so mesh_vertices() gives a usable cloud ("vertices as points",
// like the SHREC meshes); the surface is not watertight (inner, overlapping parts remain) and triangle
// winding is not consistent. Deterministic per (category, seed) on a given platform.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// {"human", "chair", "table", "mechanic", "fourleg"}: the SHREC folder names.
std::vector<std::string> zoo_categories();

struct ZooOptions {
  size_t target_vertices = 6000;  // approximate vertex count of a shape (the spacing adapts)
};

// kInvalidArgument for a category not in zoo_categories().
Expected<Mesh> make_zoo_shape(std::string_view category, uint64_t seed, const ZooOptions& options = {});

struct LabelledMesh {
  std::string category;
  uint64_t seed = 0;  // make_zoo_shape(category, seed) rebuilds it
  Mesh mesh;
  std::string id;         // its index among its category's shapes: "category/id" names it
  bool any_pose = false;  // no natural up (category_size(category).any_pose: a machine part)
};

// objects_per_category shapes of every category, grouped by category in zoo_categories() order;
// object i of a category uses a seed derived from (seed, i).
std::vector<LabelledMesh> make_zoo(size_t objects_per_category, uint64_t seed, const ZooOptions& options = {});

}  // namespace glimpse
