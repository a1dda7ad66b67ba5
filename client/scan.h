// Simulating a scanner over one single 2.5D view: the order in which its points are revealed and how
// they are cut into chunks. Pure functions over plain data, deterministic for a given seed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse::client {

enum class RevealOrder {
  kTopDown,  // descending z: the paper's top-to-bottom exploring sequence (sec. 4)
  kRandom,   // a seeded shuffle
  kSweep,    // left to right along the sensor's horizontal image axis (x when there is no sensor)
};

// "top-down", "random", "sweep".
Expected<RevealOrder> ParseRevealOrder(std::string_view text);

// A permutation of the view's point indices in reveal order.
std::vector<uint32_t> RevealSequence(const Cloud& view, RevealOrder order, uint64_t seed);

// The cloud's points in `order` (indices into it), sensor kept.
Cloud Reordered(const Cloud& cloud, const std::vector<uint32_t>& order);

// Where each chunk ends (exclusive), ascending, the last = points. Exactly one of chunks (split into
// that many nearly equal chunks, at most one per point) or chunk_points (that many points per chunk,
// the last one shorter) is non-zero. No points: no chunks.
std::vector<size_t> ChunkEnds(size_t points, size_t chunks, size_t chunk_points);

}  // namespace glimpse::client
