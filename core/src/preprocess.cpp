#include "glimpse/preprocess.h"

#include <limits>

namespace glimpse {

namespace {
constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
}  // namespace

DuplicateFilter::DuplicateFilter(float tolerance_m, size_t expected_points)
    // Exact duplicates are found with a grid far finer than any sensor resolution.
    : tolerance_(tolerance_m > 0 ? tolerance_m : 0.f), cell_(tolerance_m > 0 ? tolerance_m : 1e-6f) {
  while ((size_t{1} << bits_) < 2 * expected_points) ++bits_;
  slots_.assign(size_t{1} << bits_, kEmpty);
  cells_.reserve(expected_points);
  points_.reserve(expected_points);
}

void DuplicateFilter::grow() {
  ++bits_;
  slots_.assign(size_t{1} << bits_, kEmpty);
  const size_t mask = slots_.size() - 1;
  for (uint32_t i = 0; i < cells_.size(); ++i) {
    size_t h = CellKeyHash{}(cells_[i]) >> (64 - bits_);
    while (slots_[h] != kEmpty && !(cells_[slots_[h]] == cells_[i])) h = (h + 1) & mask;
    if (slots_[h] == kEmpty) slots_[h] = i;  // the first kept point of a cell keeps the slot
  }
}

bool DuplicateFilter::keep(const Vec3& p) {
  if (2 * (points_.size() + 1) > slots_.size()) grow();
  const size_t mask = slots_.size() - 1;
  const CellKey key = cell_key(p, cell_);
  size_t h = CellKeyHash{}(key) >> (64 - bits_);
  while (slots_[h] != kEmpty && !(cells_[slots_[h]] == key)) h = (h + 1) & mask;
  if (slots_[h] != kEmpty && (tolerance_ > 0 || points_[slots_[h]] == p)) return false;
  if (slots_[h] == kEmpty) slots_[h] = static_cast<uint32_t>(points_.size());
  points_.push_back(p);
  cells_.push_back(key);
  return true;
}

Cloud clean(const Cloud& cloud, float duplicate_tolerance_m, CleanReport* report) {
  CleanReport r;
  r.input = cloud.points.size();
  Cloud out;
  out.sensor = cloud.sensor;
  out.points.reserve(cloud.points.size());
  DuplicateFilter filter(duplicate_tolerance_m, cloud.points.size());
  for (const Vec3& p : cloud.points) {
    if (!p.allFinite()) {
      ++r.non_finite;
    } else if (!filter.keep(p)) {
      ++r.duplicates;
    } else {
      out.points.push_back(p);
    }
  }
  r.kept = out.points.size();
  if (report) *report = r;
  return out;
}

}  // namespace glimpse
