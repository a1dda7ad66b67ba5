// Convex hull volume through qhull's reentrant C library (libqhull_r), kept quiet on stderr.
#include <cstdio>
#include <span>
#include <vector>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "glimpse/features/descriptor.h"

namespace glimpse {

namespace {
// qhull writes diagnostics to a FILE*; ours go to /dev/null so no chatter reaches a user's stderr.
FILE* quiet_sink() {
  static FILE* sink = [] {
    FILE* f = std::fopen("/dev/null", "w");
    return f ? f : std::tmpfile();
  }();
  return sink;
}
}  // namespace

double convex_hull_volume(std::span<const Vec3> points) {
  if (points.size() < 4) return 0.0;
  std::vector<coordT> coords;
  coords.reserve(points.size() * 3);
  for (const Vec3& p : points) {
    coords.push_back(p.x());
    coords.push_back(p.y());
    coords.push_back(p.z());
  }
  qhT qh_storage;
  qhT* qh = &qh_storage;
  FILE* sink = quiet_sink();
  if (!sink) return 0.0;
  qh_zero(qh, sink);
  char options[] = "qhull FA Pp";
  const int exitcode = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False, options,
                                    nullptr, sink);
  const double volume = exitcode == 0 ? qh->totvol : 0.0;
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return volume > 0 ? volume : 0.0;
}

}  // namespace glimpse
