// What a real scan needs before anything is measured on it: the floor it stood on removed (RANSAC
// plane, PCL SACSegmentation), stray returns dropped (RadiusOutlierRemoval's test on a cell grid)
// and the density brought to the one the model learnt (PCL VoxelGrid). Ideal views pass through nearly
// unchanged, so the same steps run on training views and on what is classified.
#pragma once

#include <cstddef>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

struct ScanFilterParams {
  // The ground: the largest plane within max_tilt_deg of horizontal among the points in the lowest
  // ground_band_m of the cloud (from its 0.5 % height quantile). It is the ground only when
  //  - it holds at least min_ground_fraction of the cloud and spans min_ground_extent_m (a part lying
  //    flat has a plane at its bottom too);
  //  - something stands on it (0.2 % of the cloud, at least 30 points: a small part on a large floor) and
  //    next to nothing (1 %) lies under it: a table top seen alone (the first points of a top-down
  //    scan) is the object;
  //  - it reaches beyond the footprint of what rises 2.5 inlier distances above it, by 5 cm or a tenth
  //    of the object, on ground_min_sides of the 4 horizontal sides (a sensor sees floor in front and
  //    beside; the field of view may cut one side), where a base plate or flange lies within it;
  //  - it is a surface, not a few bars (min_ground_fill: a star base, a sled's runners).
  // Every point within ground_distance_m of it, or under it, goes. No ideal view of SHREC or PSB (500
  // views) loses a point to it.
  bool remove_ground = true;
  float ground_distance_m = 0.04f;  // RANSAC inlier distance: 2.5 sigma of a depth camera at 3.2 m
  float max_tilt_deg = 10.f;
  float ground_band_m = 0.25f;
  double min_ground_fraction = 0.05;
  int ground_min_sides = 2;
  float min_ground_extent_m = 0.6f;  // a floor seen by a sensor spans more than this; a part's flat face less
  double min_ground_fill = 0.3;  // share of its bounding rectangle's cells (2 cm or 1/50) it covers
  // Stray returns: a point with fewer than outlier_min_neighbours others within outlier_radius_spacings
  // x the cloud's median spacing. (PCL's StatisticalOutlierRemoval, k = 16 and 2.5 sigma, took 7.6 % of
  // a noisy 1 m plane: its whole border, whose mean neighbour distance is 20 % above the interior's;
  // a view's silhouette is where its shape is.)
  bool remove_outliers = true;
  // (4 spacings and 4 neighbours took 2.0 % of SHREC's ideal views, their sparse grazing strips; 5 and 2
  // take 0.08 %, and strays 10 spacings from anything still go.)
  float outlier_radius_spacings = 5.f;
  int outlier_min_neighbours = 2;
  // Voxel grid down to this relative density (see relative_density; 0 = no downsampling) when the
  // cloud is more than 2 x denser (views of one model differ by less): leaf = robust extent /
  // sqrt(target). A sparser cloud is left alone.
  double relative_density = 0;
};

struct ScanFilterReport {
  size_t input = 0, ground = 0, outliers = 0, kept = 0;
  float voxel_m = 0;  // 0: not downsampled
};

// Each step alone; the sensor is kept. Points keep their order except through the voxel grid (one
// centroid per occupied voxel, in PCL's voxel order).
Cloud remove_ground_plane(const Cloud& cloud, const ScanFilterParams& params, size_t* removed = nullptr);
Cloud remove_isolated_points(const Cloud& cloud, float radius_spacings, int min_neighbours, size_t* removed = nullptr);
Cloud voxel_downsample(const Cloud& cloud, float leaf_m);

// Isolated points, then the ground, then density. Deterministic.
Cloud filter_scan(const Cloud& cloud, const ScanFilterParams& params, ScanFilterReport* report = nullptr);

// The largest extent along x, y or z between the 1st and 99th percentiles: a bounding box that a few
// stray points do not blow up.
float robust_extent(const Points& points);

// Points per square of the cloud's robust extent: the surface density k / (pi r_k^2)
// (r_k the median distance to the k = 12th neighbour, which random samples and a sensor's pixel grid
// give alike) times extent^2. Independent of the object's size, so one figure says how densely the
// training views sampled objects of every size. 0 for fewer than 13 points.
double relative_density(const Points& points);

}  // namespace glimpse
