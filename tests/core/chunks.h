// A view cut into chunks as a stream sends it: top-down, in random order or swept along x, about n
// chunks of random sizes (seeded), with or without the view's sensor; and the chunks joined again.
#pragma once

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/views/exploration.h"

namespace glimpse::test {

enum class Order { kTopDown, kRandom, kSweep };

// The view's points in the given order, cut into chunks of random sizes (about `n` chunks, seeded).
inline std::vector<Cloud> chunks_of(const Cloud& view, size_t n, Order order_kind, uint64_t seed, bool sensor = true) {
  std::vector<uint32_t> order(view.points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937_64 rng(seed);
  if (order_kind == Order::kRandom) {
    for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  } else if (order_kind == Order::kTopDown) {
    order = top_down_order(view.points);
  } else {  // a sweep along x, as a scanner passing by
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return view.points[a].x() < view.points[b].x(); });
  }
  std::vector<Cloud> out;
  for (size_t i = 0; i < order.size();) {
    const size_t mean = std::max<size_t>(1, order.size() / std::max<size_t>(1, n));
    const size_t size = n == 1 ? order.size() : 1 + rng() % (2 * mean);
    Cloud c;
    if (sensor) c.sensor = view.sensor;
    for (size_t k = 0; k < size && i < order.size(); ++k, ++i) c.points.push_back(view.points[order[i]]);
    out.push_back(std::move(c));
  }
  return out;
}

inline Cloud concatenated(const std::vector<Cloud>& chunks) {
  Cloud all;
  for (const Cloud& c : chunks) {
    all.points.insert(all.points.end(), c.points.begin(), c.points.end());
    if (c.sensor) all.sensor = c.sensor;
  }
  return all;
}

}  // namespace glimpse::test
