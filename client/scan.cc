#include "client/scan.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <numeric>
#include <random>

#include "glimpse/views/exploration.h"

namespace glimpse::client {

Expected<RevealOrder> ParseRevealOrder(std::string_view text) {
  if (text == "top-down") return RevealOrder::kTopDown;
  if (text == "random") return RevealOrder::kRandom;
  if (text == "sweep") return RevealOrder::kSweep;
  return invalid_argument("unknown order '" + std::string(text) + "' (valid: top-down, random, sweep)");
}

std::vector<uint32_t> RevealSequence(const Cloud& view, RevealOrder order, uint64_t seed) {
  const Points& points = view.points;
  if (order == RevealOrder::kTopDown) return top_down_order(points);

  std::vector<uint32_t> idx(points.size());
  std::iota(idx.begin(), idx.end(), 0u);
  if (order == RevealOrder::kRandom) {
    // Fisher-Yates with mt19937_64 (fully specified), not std::shuffle (library-defined).
    std::mt19937_64 rng(seed);
    for (size_t i = idx.size(); i > 1; --i) std::swap(idx[i - 1], idx[rng() % i]);
    return idx;
  }
  // Sweep: the camera looks from the sensor at the centroid; its horizontal image axis is
  // view_dir x up, so ascending projection on it runs left to right in the image.
  Vec3 axis = Vec3::UnitX();
  if (view.sensor && !points.empty()) {
    Vec3 centroid = Vec3::Zero();
    for (const Vec3& p : points) centroid += p;
    centroid /= static_cast<float>(points.size());
    const Vec3 right = (centroid - *view.sensor).cross(Vec3::UnitZ());
    if (right.norm() > 1e-6f) axis = right.normalized();
  }
  std::vector<float> key(points.size());
  for (size_t i = 0; i < points.size(); ++i) key[i] = points[i].dot(axis);
  std::stable_sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
  return idx;
}

Cloud Reordered(const Cloud& cloud, const std::vector<uint32_t>& order) {
  Cloud out;
  out.sensor = cloud.sensor;
  out.frame = cloud.frame;
  out.points.reserve(order.size());
  for (uint32_t i : order) out.points.push_back(cloud.points[i]);
  return out;
}

std::vector<size_t> ChunkEnds(size_t points, size_t chunks, size_t chunk_points) {
  std::vector<size_t> ends;
  if (points == 0) return ends;
  if (chunk_points > 0) {
    for (size_t end = chunk_points; end < points; end += chunk_points) ends.push_back(end);
    ends.push_back(points);
    return ends;
  }
  chunks = std::clamp<size_t>(chunks, 1, points);
  for (size_t c = 1; c <= chunks; ++c) ends.push_back(points * c / chunks);  // nearly equal, last = points
  return ends;
}

}  // namespace glimpse::client
