#include "glimpse/geometry/neighbourhoods.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>

namespace glimpse {

namespace {
struct PointsAdaptor {
  const Points* pts;
  size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return (*pts)[i][static_cast<int>(dim)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointsAdaptor>,
                                                 PointsAdaptor, 3, uint32_t>;

// Neighbourhoods in ascending index order: every sum over a neighbourhood then adds in the same order
// whichever index found it, so a kd-tree over a cloud and the voxel hash of the same scan give
// bit-identical surfaces. Insertion sort: neighbourhoods are a few dozen points, mostly in order.
void sort_by_index(std::vector<Neighbour>& v) {
  for (size_t i = 1; i < v.size(); ++i) {
    const Neighbour x = v[i];
    size_t j = i;
    for (; j > 0 && v[j - 1].index > x.index; --j) v[j] = v[j - 1];
    v[j] = x;
  }
}

}  // namespace

void NeighbourIndex::radius(const Vec3& query, float radius, std::vector<Neighbour>& out) const {
  radius_any_order(query, radius, out);
  sort_by_index(out);
}

struct KdTree::Impl {
  explicit Impl(const Points& p) : adaptor{&p}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    if (!p.empty()) tree.buildIndex();
  }
  PointsAdaptor adaptor;
  Tree tree;
};

KdTree::KdTree(const Points& points) : impl_(std::make_unique<Impl>(points)) {}
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;
const Points& KdTree::points() const { return *impl_->adaptor.pts; }

void KdTree::radius_any_order(const Vec3& query, float radius, std::vector<Neighbour>& out) const {
  out.clear();
  if (impl_->adaptor.pts->empty()) return;
  // nanoflann 1.4 returns (index, squared distance) pairs; it wants the squared radius.
  thread_local std::vector<std::pair<uint32_t, float>> found;
  found.clear();
  nanoflann::SearchParams params(32, 0.f, false);
  // Distances and the boundary test as VoxelIndex computes them, so both indexes return the same
  // neighbourhoods to the last bit: nanoflann's own (summed in another order) only preselects.
  const float r2 = radius * radius;
  impl_->tree.radiusSearch(query.data(), r2 * (1.f + 1e-4f), found, params);
  out.reserve(found.size());
  const Points& pts = *impl_->adaptor.pts;
  for (const auto& [i, d] : found)
    if (const float e = (pts[i] - query).squaredNorm(); e <= r2) out.push_back({i, e});
}

void KdTree::nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const {
  out.clear();
  k = std::min(k, impl_->adaptor.pts->size());
  if (k == 0) return;
  // A few more candidates than asked, re-measured and ordered as VoxelIndex does (distance, then
  // index), so ties and last-bit differences cannot pick another k-th neighbour.
  const size_t want = std::min(k + 8, impl_->adaptor.pts->size());
  thread_local std::vector<uint32_t> idx;
  thread_local std::vector<float> dist;
  idx.resize(want);
  dist.resize(want);
  const size_t n = impl_->tree.knnSearch(query.data(), want, idx.data(), dist.data());
  const Points& pts = *impl_->adaptor.pts;
  for (size_t i = 0; i < n; ++i) out.push_back({idx[i], (pts[idx[i]] - query).squaredNorm()});
  std::sort(out.begin(), out.end(), [](const Neighbour& a, const Neighbour& b) {
    return a.distance_sq != b.distance_sq ? a.distance_sq < b.distance_sq : a.index < b.index;
  });
  out.resize(std::min(k, out.size()));
}

// ---- CellGrid ------------------------------------------------------------------------------------

namespace {
// A cell count the grid's offsets may take: a few per point, so points spread far wider than the cells
// (not a few stray ones: they are clamped, below) grow the cells instead of the memory.
double cells_allowed(size_t points) { return std::max(4.0 * double(points), double(1 << 16)); }

// Each axis's 1st and 99th percentiles over an evenly spaced sample of at most 1024 finite points (no
// finite point: false).
bool percentile_box(const Points& points, Vec3& lo, Vec3& hi) {
  const size_t stride = std::max<size_t>(1, points.size() / 1024);
  std::vector<float> v;
  for (int axis = 0; axis < 3; ++axis) {
    v.clear();
    for (size_t i = 0; i < points.size(); i += stride)
      if (points[i].allFinite()) v.push_back(points[i][axis]);
    if (v.empty()) return false;
    const size_t a = v.size() / 100, b = v.size() - 1 - a;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(a), v.end());
    lo[axis] = v[a];
    if (b > a) std::nth_element(v.begin() + std::ptrdiff_t(a + 1), v.begin() + std::ptrdiff_t(b), v.end());
    hi[axis] = v[b];
  }
  return true;
}
}  // namespace

float first_guess_cell(const Points& points) {
  // The percentiles' extent: a few stray far points do not inflate it.
  Vec3 lo, hi;
  if (points.empty() || !percentile_box(points, lo, hi)) return 1.f;
  const float cell = 4.f * (hi - lo).maxCoeff() / std::sqrt(float(points.size()));
  return cell > 0 && std::isfinite(cell) ? cell : 1e-3f;
}

CellGrid::CellGrid(const Points& points, float cell_m) : points_(&points) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Vec3& p : points)
    if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (!(lo.x() <= hi.x())) lo = hi = Vec3::Zero();  // no finite point
  lowest_ = lo, highest_ = hi;
  // The cells span the percentiles widened by their span on each side, where that is inside the
  // bounding box: a few stray far points are clamped into the border cells instead of stretching every
  // cell (the map from coordinate to cell stays monotone, so a query's cells still hold every point
  // within its reach).
  if (Vec3 plo, phi; percentile_box(points, plo, phi)) {
    const Vec3 widen = phi - plo;
    lo = lo.cwiseMax(plo - widen), hi = hi.cwiseMin(phi + widen);
  }
  origin_ = lo;
  double cell = cell_m > 0 && std::isfinite(cell_m) ? double(cell_m) : 1.0;
  const Eigen::Vector3d span = (hi - lo).cast<double>();
  auto cells = [&](double c) { return (std::floor(span.x() / c) + 1) * (std::floor(span.y() / c) + 1) * (std::floor(span.z() / c) + 1); };
  while (cells(cell) > cells_allowed(points.size())) cell *= 2;
  cell_ = static_cast<float>(cell);
  nx_ = static_cast<int64_t>(std::floor(span.x() / cell_)) + 1;
  ny_ = static_cast<int64_t>(std::floor(span.y() / cell_)) + 1;
  nz_ = static_cast<int64_t>(std::floor(span.z() / cell_)) + 1;
  // In double, as the queries' boxes: the same monotone map from coordinate to cell.
  auto axis = [&](float v, float o, int64_t n) {
    const double c = std::floor((double(v) - double(o)) / double(cell_));
    return c >= 0 ? static_cast<int64_t>(std::min(c, double(n - 1))) : int64_t{0};  // NaN -> 0
  };
  std::vector<uint32_t> cell_of(points.size());
  start_.assign(static_cast<size_t>(nx_ * ny_ * nz_) + 1, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    cell_of[i] = static_cast<uint32_t>((axis(p.x(), lo.x(), nx_) * ny_ + axis(p.y(), lo.y(), ny_)) * nz_ +
                                       axis(p.z(), lo.z(), nz_));
    ++start_[cell_of[i] + 1];
  }
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  order_.resize(points.size());
  binned_.resize(points.size());
  std::vector<uint32_t> next(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < points.size(); ++i) {  // ascending i: each cell's run ascends
    const uint32_t j = next[cell_of[i]]++;
    order_[j] = static_cast<uint32_t>(i);
    binned_[j] = points[i];
  }
}

std::unique_ptr<NeighbourIndex> fixed_cloud_index(const Points& points, float radius) {
  auto grid = std::make_unique<CellGrid>(points, radius);
  if (grid->cell() > 2 * radius) return std::make_unique<KdTree>(points);
  return grid;
}

std::unique_ptr<NeighbourIndex> first_guess_index(const Points& points) {
  return fixed_cloud_index(points, first_guess_cell(points));
}

void CellGrid::radius_any_order(const Vec3& q, float radius, std::vector<Neighbour>& out) const {
  out.clear();
  if (order_.empty() || !(radius >= 0)) return;
  const float r2 = radius * radius;
  // The box is a little wider than the ball, so a point the float test below accepts is inside it.
  const double reach = double(radius) * (1 + 1e-5) + 1e-30;
  int64_t lo[3], hi[3];
  const int64_t n[3] = {nx_, ny_, nz_};
  for (int a = 0; a < 3; ++a) {
    // A box outside every point finds nothing (nor does a NaN query).
    if (!(double(q[a]) + reach >= double(lowest_[a]) && double(q[a]) - reach <= double(highest_[a]))) return;
    // Clamped as the points' cells are: a point outside the cells' span lies in a border cell.
    const double from = std::floor((double(q[a]) - reach - double(origin_[a])) / double(cell_));
    const double to = std::floor((double(q[a]) + reach - double(origin_[a])) / double(cell_));
    lo[a] = static_cast<int64_t>(std::clamp(from, 0.0, double(n[a] - 1)));
    hi[a] = static_cast<int64_t>(std::clamp(to, 0.0, double(n[a] - 1)));
  }
  // Each column of cells along z is one run of binned_. Every candidate is written and the count
  // advanced only when it is inside: no branch for the test, which goes either way.
  size_t candidates = 0;
  for (int64_t x = lo[0]; x <= hi[0]; ++x)
    for (int64_t y = lo[1]; y <= hi[1]; ++y) {
      const int64_t column = (x * ny_ + y) * nz_;
      candidates += start_[static_cast<size_t>(column + hi[2] + 1)] - start_[static_cast<size_t>(column + lo[2])];
    }
  out.resize(candidates);
  Neighbour* w = out.data();
  for (int64_t x = lo[0]; x <= hi[0]; ++x)
    for (int64_t y = lo[1]; y <= hi[1]; ++y) {
      const int64_t column = (x * ny_ + y) * nz_;
      const uint32_t from = start_[static_cast<size_t>(column + lo[2])], to = start_[static_cast<size_t>(column + hi[2] + 1)];
      for (uint32_t j = from; j < to; ++j) {
        const float d = (binned_[j] - q).squaredNorm();
        *w = {order_[j], d};
        w += d <= r2;
      }
    }
  out.resize(static_cast<size_t>(w - out.data()));
}

void CellGrid::nearest(const Vec3& q, size_t k, std::vector<Neighbour>& out) const {
  out.clear();
  k = std::min(k, order_.size());
  if (k == 0) return;
  // Grow the search radius until k points are inside it (as VoxelIndex); the k nearest are then exact.
  const double far = (highest_ - lowest_).cast<double>().norm() + (q - lowest_).cast<double>().norm();
  float radius = cell_;
  for (;;) {
    radius_any_order(q, radius, out);  // ordered below
    if (out.size() >= k || !(radius < far)) break;
    radius *= 2;
  }
  k = std::min(k, out.size());
  auto order = [](const Neighbour& a, const Neighbour& b) {
    return a.distance_sq != b.distance_sq ? a.distance_sq < b.distance_sq : a.index < b.index;
  };
  std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(k), out.end(), order);
  out.resize(k);
}

// ---- VoxelIndex ----------------------------------------------------------------------------------

VoxelIndex::VoxelIndex(float cell_m) : cell_(cell_m > 0 ? cell_m : 1.f) {}

uint32_t VoxelIndex::add(const Vec3& p) {
  const auto i = static_cast<uint32_t>(points_.size());
  points_.push_back(p);
  cells_[key(p)].push_back(i);
  return i;
}

void VoxelIndex::radius_any_order(const Vec3& q, float radius, std::vector<Neighbour>& out) const {
  out.clear();
  const float r2 = radius * radius;
  const CellKey lo = key(q - Vec3::Constant(radius)), hi = key(q + Vec3::Constant(radius));
  const double span = (double(hi.x) - lo.x + 1) * (double(hi.y) - lo.y + 1) * (double(hi.z) - lo.z + 1);
  if (span > static_cast<double>(cells_.size())) {
    // A query larger than the whole set: visiting the occupied cells is cheaper than the empty ones.
    for (const auto& [k, members] : cells_)
      for (uint32_t i : members) {
        const float d = (points_[i] - q).squaredNorm();
        if (d <= r2) out.push_back({i, d});
      }
    return;
  }
  for (int64_t x = lo.x; x <= hi.x; ++x)
    for (int64_t y = lo.y; y <= hi.y; ++y)
      for (int64_t z = lo.z; z <= hi.z; ++z) {
        const auto it = cells_.find({x, y, z});
        if (it == cells_.end()) continue;
        for (uint32_t i : it->second) {
          const float d = (points_[i] - q).squaredNorm();
          if (d <= r2) out.push_back({i, d});
        }
      }
}

void VoxelIndex::nearest(const Vec3& q, size_t k, std::vector<Neighbour>& out) const {
  out.clear();
  k = std::min(k, points_.size());
  if (k == 0) return;
  // Grow the search radius until k points are inside it; the k nearest are then exact.
  float radius = cell_;
  for (;;) {
    radius_any_order(q, radius, out);  // ordered below
    if (out.size() >= k) break;
    radius *= 2;
  }
  auto order = [](const Neighbour& a, const Neighbour& b) {
    return a.distance_sq != b.distance_sq ? a.distance_sq < b.distance_sq : a.index < b.index;
  };
  std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(k), out.end(), order);
  out.resize(k);
}

float median_knn_distance(const NeighbourIndex& tree, size_t k, size_t sample) {
  const size_t ks[] = {k};
  return median_knn_distances(tree, ks, sample)[0];
}

std::vector<float> median_knn_distances(const NeighbourIndex& tree, std::span<const size_t> ks_in, size_t sample) {
  const Points& pts = tree.points();
  std::vector<float> out(ks_in.size(), 0.f);
  if (pts.size() < 2 || ks_in.empty()) return out;
  std::vector<size_t> ks(ks_in.begin(), ks_in.end());
  for (size_t& k : ks) k = std::min(k, pts.size() - 1);
  const size_t kmax = *std::max_element(ks.begin(), ks.end());
  if (kmax == 0) return out;
  const size_t step = std::max<size_t>(1, pts.size() / std::max<size_t>(sample, 1));
  std::vector<size_t> at;
  for (size_t i = 0; i < pts.size(); i += step) at.push_back(i);
  std::vector<Neighbour> nn;
  auto kth = [&](size_t i, size_t k) {
    tree.nearest(pts[i], k + 1, nn);  // the point itself comes first
    return std::sqrt(nn[k].distance_sq);
  };
  auto median = [](std::vector<float>& v) {
    auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  // A k-nearest search costs about two radius searches, so: the exact k-th distance at a few samples
  // gives a radius R a little above the typical one (for the largest k asked); at every sample the k-th
  // smallest distance within R is exact, and a sample with fewer than k + 1 points within R has its k-th
  // distance beyond R. While those are fewer than half, the median is exactly the one of the k-th
  // distances. One radius search per sample serves every k.
  std::vector<float> pilot;
  for (size_t j = 0; j < at.size(); j += std::max<size_t>(1, at.size() / 16)) pilot.push_back(kth(at[j], kmax));
  const float R = 1.2f * median(pilot);
  std::vector<std::vector<float>> d(ks.size());
  for (auto& v : d) v.reserve(at.size());
  auto closer = [](const Neighbour& a, const Neighbour& b) { return a.distance_sq < b.distance_sq; };
  for (size_t i : at) {
    tree.radius_any_order(pts[i], R, nn);  // only the k-th distance is read
    for (size_t q = 0; q < ks.size(); ++q) {
      const size_t k = ks[q];
      if (k == 0 || nn.size() < k + 1) {
        d[q].push_back(k == 0 ? 0.f : std::numeric_limits<float>::infinity());
        continue;
      }
      std::nth_element(nn.begin(), nn.begin() + static_cast<std::ptrdiff_t>(k), nn.end(), closer);
      d[q].push_back(std::sqrt(nn[k].distance_sq));
    }
  }
  for (size_t q = 0; q < ks.size(); ++q) {
    out[q] = median(d[q]);
    if (std::isfinite(out[q])) continue;
    for (size_t j = 0; j < at.size(); ++j) d[q][j] = kth(at[j], ks[q]);
    out[q] = median(d[q]);
  }
  return out;
}

float snap_radius(float r) {
  if (!(r > 0) || !std::isfinite(r)) return r;
  return std::exp2(std::round(8.f * std::log2(r)) / 8.f);
}

Density estimate_density(const NeighbourIndex& index, float fixed_radius_m, int support_neighbours) {
  Density d;
  d.knn_distance_m = median_knn_distance(index, static_cast<size_t>(std::max(1, support_neighbours)));
  d.support_radius_m = fixed_radius_m > 0 ? fixed_radius_m : snap_radius(d.knn_distance_m);
  d.normal_radius_m = d.support_radius_m;
  d.boundary_band_m = d.support_radius_m;
  return d;
}

}  // namespace glimpse
