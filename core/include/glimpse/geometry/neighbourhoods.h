// Neighbourhoods of a point set (sec. 3.2.1): the queries every stage makes, over a fixed cloud
// (cells of one size, or a kd-tree) or a growing scan (voxel hash), and the one density estimate every
// radius derives from.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/spatial_hash.h"

namespace glimpse {

struct Neighbour {
  uint32_t index;
  float distance_sq;
};

// Neighbourhood queries over a point set. Every stage that visits neighbourhoods takes this, so a
// static cloud (CellGrid, KdTree) and a growing scan (VoxelIndex) share the same code.
class NeighbourIndex {
 public:
  virtual ~NeighbourIndex() = default;
  // Every point within `radius` of `query` (the query point itself included when it is in the set),
  // in ascending index order (sums over a neighbourhood do not depend on which index found it).
  void radius(const Vec3& query, float radius, std::vector<Neighbour>& out) const;
  // The same neighbours in any order, for callers that only count them or rank them by distance.
  virtual void radius_any_order(const Vec3& query, float radius, std::vector<Neighbour>& out) const = 0;
  // The `k` nearest points, nearest first (ties by index).
  virtual void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const = 0;
  virtual const Points& points() const = 0;
};

// A kd-tree over a fixed point set (nanoflann); the points must outlive the tree and stay unchanged.
class KdTree final : public NeighbourIndex {
 public:
  explicit KdTree(const Points& points);
  ~KdTree() override;
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;

  void radius_any_order(const Vec3& query, float radius, std::vector<Neighbour>& out) const override;
  void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const override;
  const Points& points() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A fixed point set binned into cubic cells of one size, each cell's points stored together: a radius
// query about the cell size scans a few contiguous runs instead of walking a tree. Same neighbourhoods
// as KdTree and VoxelIndex to the last bit. The points must outlive the grid and stay unchanged.
class CellGrid final : public NeighbourIndex {
 public:
  CellGrid(const Points& points, float cell_m);
  void radius_any_order(const Vec3& query, float radius, std::vector<Neighbour>& out) const override;
  void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const override;
  const Points& points() const override { return *points_; }
  // The cells' size: the one asked for, or larger when that many cells would not fit (points spread far
  // wider than the cell), where a kd-tree answers faster. A few stray far points do not count: the
  // cells span the points' percentiles (widened), and points outside lie in the border cells.
  float cell() const { return cell_; }

 private:
  const Points* points_;
  float cell_ = 1;
  Vec3 lowest_ = Vec3::Zero(), highest_ = Vec3::Zero();  // the finite points' bounding box
  Vec3 origin_ = Vec3::Zero();                            // the cells' lowest corner (points below: clamped)
  int64_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<uint32_t> start_;  // cell c's points are order_[start_[c] .. start_[c + 1]), z fastest
  std::vector<uint32_t> order_;  // point indices, by cell, ascending within a cell
  Points binned_;                // the points in order_'s order
};

// The index for many queries about `radius` wide over a fixed cloud: cells of that size, or a kd-tree
// when that many cells would not fit (points spread far wider than the radius would make each cell hold
// many). Both give the same answers; only the speed differs.
std::unique_ptr<NeighbourIndex> fixed_cloud_index(const Points& points, float radius);

// A cell for a cloud whose density is not known yet: about four spacings of a surface sample filling
// the cloud's extent (between the 1st and 99th percentiles, so a stray far point does not inflate it).
// It sets only how much a grid's query scans, never what it finds.
float first_guess_cell(const Points& points);
// The index for such a cloud (its density's queries): fixed_cloud_index at the first-guess cell.
std::unique_ptr<NeighbourIndex> first_guess_index(const Points& points);

// A growing point set hashed into cubic cells (append-only): insertion and queries cost what the
// neighbourhood holds, not what the set holds. Radius queries are fastest for radius <= cell size.
class VoxelIndex final : public NeighbourIndex {
 public:
  explicit VoxelIndex(float cell_m);
  uint32_t add(const Vec3& p);  // returns the new point's index
  void radius_any_order(const Vec3& query, float radius, std::vector<Neighbour>& out) const override;
  void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const override;
  const Points& points() const override { return points_; }
  float cell() const { return cell_; }

 private:
  CellKey key(const Vec3& p) const { return cell_key(p, cell_); }
  float cell_;
  Points points_;
  std::unordered_map<CellKey, std::vector<uint32_t>, CellKeyHash> cells_;
};

// Median distance from a point to its k-th nearest other point (over a deterministic sample of at
// most `sample` points); 0 for fewer than 2 points. k = 1 gives the median spacing.
float median_knn_distance(const NeighbourIndex& tree, size_t k, size_t sample = 300);
// The same for several k at once (one radius search per sample serves them all), in ks' order.
std::vector<float> median_knn_distances(const NeighbourIndex& tree, std::span<const size_t> ks, size_t sample = 300);


// The density of a cloud and every radius derived from it (sec. 3.2.1: "as small a radius as possible"
// for the density): one estimate, recorded in the diagnostics, fixed the same way for a whole cloud, a
// stream and training.
struct Density {
  float knn_distance_m = 0;    // median distance to the k-th nearest point (k = the support neighbours)
  float support_radius_m = 0;  // r: the local surfaces' neighbourhood; the knn distance snapped (below)
  float normal_radius_m = 0;   // VFH's normals: the local surfaces' own, over r
  float boundary_band_m = 0;   // sec. 3.2.2: boundary points' neighbourhood without keypoints: r
};

// The automatic radius is snapped to a grid of 2^(1/8) steps (9 %, below what moves a feature): a
// stream re-estimates the density as it grows and recomputes its surfaces only when the snapped
// radius changes, and ends on the radius its whole cloud gets. A fixed radius (> 0) is used as given.
float snap_radius(float r);
Density estimate_density(const NeighbourIndex& index, float fixed_radius_m, int support_neighbours);

}  // namespace glimpse
