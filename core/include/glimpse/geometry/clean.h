// Cleaning a cloud before anything measures it: non-finite points and duplicates out, in one rule
// shared by whole clouds and growing scans.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/spatial_hash.h"

namespace glimpse {

struct CleanReport {
  size_t input = 0;
  size_t non_finite = 0;   // NaN/Inf coordinates dropped
  size_t duplicates = 0;   // points closer than the tolerance to an earlier kept point
  size_t kept = 0;
};

// The duplicate rule: a point is a duplicate when it falls in the grid cell (of `tolerance_m`) of a
// point kept before it; with tolerance 0 when it equals a point kept before it. Remembers the kept
// points' cells, so a scan fed chunk by chunk keeps exactly the points its whole cloud keeps.
class DuplicateFilter {
 public:
  explicit DuplicateFilter(float tolerance_m, size_t expected_points = 0);
  // True when `p` (finite) is kept; it is then remembered.
  bool keep(const Vec3& p);
  size_t kept() const { return cells_.size(); }

 private:
  void grow();
  float tolerance_;
  int bits_ = 4;
  std::vector<uint32_t> slots_;  // open addressing, linear probing: slot -> kept point
  std::vector<CellKey> cells_;   // per kept point: its cell, or with no tolerance the point itself
};

// Drops NaN/Inf points and duplicates (DuplicateFilter, first one kept). Order of the kept points is
// preserved; the sensor is kept.
Cloud clean(const Cloud& cloud, float duplicate_tolerance_m, CleanReport* report = nullptr);

// clean()'s rule on a scan whose points may carry their own sensors: appends the finite points `filter`
// keeps to `out` and, when `out_sensors` is given, each one's sensor (point_sensors[i], or the cloud's
// when point_sensors is empty). One filter fed chunk by chunk keeps what the whole scan would.
void clean_into(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors, DuplicateFilter& filter,
                Cloud& out, std::vector<std::optional<Vec3>>* out_sensors);

}  // namespace glimpse
