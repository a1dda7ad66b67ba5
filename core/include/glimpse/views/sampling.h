// Points from a mesh (sec. 3.4): its vertices, or area-weighted samples of its surface, and the full 3D
// cloud of one object of the protocol, seeded by the object's name.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "glimpse/cloud.h"

namespace glimpse {

// Sec. 3.4: "representing the models by the vertices of the meshes".
Cloud mesh_vertices(const Mesh& mesh);

// Area-weighted uniform samples on the triangles: round(area * points_per_m2) points (capped at
// 50M), deterministic for a given seed. Degenerate triangles get none.
Cloud sample_surface(const Mesh& mesh, double points_per_m2, uint64_t seed);

// Total surface area of the triangles, m^2.
double surface_area(const Mesh& mesh);

// The seed of one object's samples and poses, from (seed, "category/id"): the same wherever and in
// whatever order the object is listed, so the client's views of a folder are the lab's.
uint64_t object_seed(uint64_t seed, std::string_view key);

// An object's full 3D cloud: `points` area-weighted samples (seeded), or its vertices when points is 0
// or the mesh has no area.
Points object_cloud(const Mesh& mesh, size_t points, uint64_t seed);

}  // namespace glimpse
