#include "glimpse/geometry/normal_orientation.h"

#include <algorithm>
#include <cmath>
#include <queue>

namespace glimpse {

void orient_normals_propagated(const NeighbourIndex& tree, std::vector<LocalSurface>& surfaces, int k) {
  const Points& pts = tree.points();
  const size_t n = pts.size();
  if (n == 0) return;
  auto flip = [](LocalSurface& s) {
    s.normal = -s.normal;
    const float k1 = s.k1;
    s.k1 = -s.k2;
    s.k2 = -k1;
  };
  // The signs a caller hands in must not matter (a growing scan refits some points and not others):
  // start from a canonical sign, the normal's first non-zero of z, y, x positive. A component whose
  // outward test below is a tie (a lone point) then keeps that sign, whatever came before.
  for (LocalSurface& s : surfaces) {
    if (!s.valid) continue;
    const Vec3& m = s.normal;
    const float key = m.z() != 0 ? m.z() : m.y() != 0 ? m.y() : m.x();
    if (key < 0) flip(s);
  }
  // Components are grown from roots in a fixed order (highest point first, ties by index); within a
  // component each normal is flipped to agree with its parent in the spanning tree.
  std::vector<uint32_t> roots(n);
  for (uint32_t i = 0; i < n; ++i) roots[i] = i;
  std::stable_sort(roots.begin(), roots.end(), [&](uint32_t a, uint32_t b) { return pts[a].z() > pts[b].z(); });
  constexpr uint32_t kUnvisited = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> component(n, kUnvisited);
  std::vector<uint32_t> members;
  using Item = std::tuple<float, uint32_t, uint32_t>;  // weight, index, parent
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  std::vector<Neighbour> nb;
  uint32_t next_component = 0;
  for (uint32_t root : roots) {
    if (component[root] != kUnvisited || !surfaces[root].valid) continue;
    const uint32_t id = next_component++;
    members.clear();
    queue.emplace(0.f, root, root);
    while (!queue.empty()) {
      const auto [w, i, parent] = queue.top();
      queue.pop();
      if (component[i] != kUnvisited) continue;
      component[i] = id;
      members.push_back(i);
      if (i != parent && surfaces[i].normal.dot(surfaces[parent].normal) < 0) flip(surfaces[i]);
      tree.nearest(pts[i], static_cast<size_t>(k) + 1, nb);
      for (const Neighbour& q : nb) {
        if (component[q.index] != kUnvisited || !surfaces[q.index].valid) continue;
        const float weight = 1.f - std::abs(surfaces[i].normal.dot(surfaces[q.index].normal));
        queue.emplace(weight, q.index, i);
      }
    }
    // The sign of a whole component is arbitrary so far: turn it outward (most normals pointing away
    // from the component's centroid), which does not depend on the cloud's pose.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (uint32_t i : members) centroid += pts[i].cast<double>();
    centroid /= static_cast<double>(members.size());
    double outward = 0;
    for (uint32_t i : members) outward += surfaces[i].normal.cast<double>().dot(pts[i].cast<double>() - centroid);
    if (outward < 0)
      for (uint32_t i : members) flip(surfaces[i]);
  }
}

}  // namespace glimpse
