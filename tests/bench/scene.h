// The benchmarks' common input: a single view of a chair-sized scene (boxes, a ball, a post), points
// facing the camera only, thinned evenly to 10k points so that every part of the scene stays in it.
#pragma once

#include <algorithm>

#include "../core/shapes.h"
#include "glimpse/cloud.h"

namespace glimpse::bench {

inline Cloud single_view(size_t target) {
  const Vec3 camera(2.f, 1.5f, 1.5f);
  Points all;
  for (const Vec3& p : test::cube(0.45f, 0.0062f)) all.push_back(p);
  for (const Vec3& p : test::sphere(0.12f, 6000, Vec3(0.2f, 0.2f, 0.6f))) all.push_back(p);
  for (const Vec3& p : test::cylinder(0.03f, 0.8f, 0.0062f)) all.push_back(p + Vec3(0.6f, 0.1f, 0.4f));
  Cloud view{{}, camera, {}};
  const Vec3 centre(0.25f, 0.25f, 0.3f);
  for (const Vec3& p : all)
    if ((p - centre).dot(camera - centre) > 0) view.points.push_back(p);
  Cloud thinned{{}, camera, {}};
  const double step = std::max(1.0, static_cast<double>(view.points.size()) / static_cast<double>(target));
  for (double i = 0; i < static_cast<double>(view.points.size()); i += step)
    thinned.points.push_back(view.points[static_cast<size_t>(i)]);
  return thinned;
}

inline const Cloud& view10k() {
  static const Cloud c = single_view(10000);
  return c;
}

}  // namespace glimpse::bench
