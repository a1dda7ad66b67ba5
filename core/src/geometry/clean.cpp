#include "glimpse/geometry/clean.h"

#include <bit>
#include <limits>

namespace glimpse {

namespace {
constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();

// With no tolerance a point's key is the point itself (its coordinates' bits, -0 as +0), so every
// distinct point has its own slot and a copy of any kept point is found.
CellKey exact_key(const Vec3& p) {
  auto bits = [](float v) { return int64_t(std::bit_cast<uint32_t>(v + 0.0f)); };
  return {bits(p.x()), bits(p.y()), bits(p.z())};
}
}  // namespace

DuplicateFilter::DuplicateFilter(float tolerance_m, size_t expected_points)
    : tolerance_(tolerance_m > 0 ? tolerance_m : 0.f) {
  while ((size_t{1} << bits_) < 2 * expected_points) ++bits_;
  slots_.assign(size_t{1} << bits_, kEmpty);
  cells_.reserve(expected_points);
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
  if (2 * (cells_.size() + 1) > slots_.size()) grow();
  const size_t mask = slots_.size() - 1;
  const CellKey key = tolerance_ > 0 ? cell_key(p, tolerance_) : exact_key(p);
  size_t h = CellKeyHash{}(key) >> (64 - bits_);
  while (slots_[h] != kEmpty && !(cells_[slots_[h]] == key)) h = (h + 1) & mask;
  if (slots_[h] != kEmpty) return false;
  slots_[h] = static_cast<uint32_t>(cells_.size());
  cells_.push_back(key);
  return true;
}

Cloud clean(const Cloud& cloud, float duplicate_tolerance_m, CleanReport* report) {
  CleanReport r;
  r.input = cloud.points.size();
  Cloud out;
  out.sensor = cloud.sensor;
  out.frame = cloud.frame;
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

void clean_into(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors, DuplicateFilter& filter,
                Cloud& out, std::vector<std::optional<Vec3>>* out_sensors) {
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Vec3& p = cloud.points[i];
    if (!p.allFinite() || !filter.keep(p)) continue;
    out.points.push_back(p);
    if (out_sensors) out_sensors->push_back(point_sensors.empty() ? cloud.sensor : point_sensors[i]);
  }
}

}  // namespace glimpse
