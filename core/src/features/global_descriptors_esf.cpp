// ESF (Wohlkinger & Vincze's Ensemble of Shape Functions), the seeded port of PCL's; VFH and PCL's own
// pipelines are in global_descriptors.cpp. No PCL header here.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "glimpse/features/global_descriptors.h"
#include "features/global_descriptors_common.h"

namespace glimpse {

using global_internal::centroid;
using global_internal::validate;

// ---------------------------------------------------------------------------------------------------
// ESF, ported from PCL 1.13 pcl/features/impl/esf.hpp. Changes: a seeded std::mt19937_64 instead of
// srand(time(nullptr)) / rand(); the voxel grid lives in the call (thread-safe); grid coordinates are
// clamped to the grid; triangle areas from the cross product instead of Heron's formula; a bounded
// number of draws, so a degenerate cloud fails instead of looping.
// The original's notice:
//
//  Software License Agreement (BSD License)
//
//  Point Cloud Library (PCL) - www.pointclouds.org
//  Copyright (c) 2010-2012, Willow Garage, Inc.
//  Copyright (c) 2012-, Open Perception, Inc.
//
//  All rights reserved.
//
//  Redistribution and use in source and binary forms, with or without modification, are permitted
//  provided that the following conditions are met:
//
//   * Redistributions of source code must retain the above copyright notice, this list of conditions
//     and the following disclaimer.
//   * Redistributions in binary form must reproduce the above copyright notice, this list of
//     conditions and the following disclaimer in the documentation and/or other materials provided
//     with the distribution.
//   * Neither the name of the copyright holder(s) nor the names of its contributors may be used to
//     endorse or promote products derived from this software without specific prior written
//     permission.
//
//  THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS" AND ANY EXPRESS OR
//  IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE IMPLIED WARRANTIES OF MERCHANTABILITY AND
//  FITNESS FOR A PARTICULAR PURPOSE ARE DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT OWNER OR
//  CONTRIBUTORS BE LIABLE FOR ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL
//  DAMAGES (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES; LOSS OF USE,
//  DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON ANY THEORY OF LIABILITY, WHETHER
//  IN CONTRACT, STRICT LIABILITY, OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT
//  OF THE USE OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
// ---------------------------------------------------------------------------------------------------
namespace {

constexpr int kGrid = 64;      // voxel grid side; the cloud is scaled into a sphere of radius kHalf
constexpr int kHalf = kGrid / 2;
constexpr int kBins = 64;      // bins per shape function
constexpr int kSamples = 20000;  // point triplets per descriptor
constexpr long kMaxDraws = 200L * kSamples;

float pcl_round(float x) { return x < 0.0f ? std::ceil(x - 0.5f) : std::floor(x + 0.5f); }

int grid_coord(float v) {
  const int g = v < 0.0f ? static_cast<int>(std::floor(v)) + kHalf : static_cast<int>(std::ceil(v)) + kHalf - 1;
  return std::clamp(g, 0, kGrid - 1);
}

struct VoxelGrid {
  std::vector<uint8_t> occupied = std::vector<uint8_t>(kGrid * kGrid * kGrid, 0);
  bool at(int x, int y, int z) const { return occupied[(x * kGrid + y) * kGrid + z] != 0; }
};

// Marks the 3x3x3 voxels around every point (PCL's voxelize9).
void voxelize9(const std::vector<Eigen::Vector3f>& pts, VoxelGrid& grid) {
  for (const Eigen::Vector3f& p : pts) {
    const int xx = grid_coord(p.x()), yy = grid_coord(p.y()), zz = grid_coord(p.z());
    for (int x = -1; x < 2; ++x)
      for (int y = -1; y < 2; ++y)
        for (int z = -1; z < 2; ++z) {
          const int xi = xx + x, yi = yy + y, zi = zz + z;
          if (xi < 0 || yi < 0 || zi < 0 || xi >= kGrid || yi >= kGrid || zi >= kGrid) continue;
          grid.occupied[(xi * kGrid + yi) * kGrid + zi] = 1;
        }
  }
}

// Bresenham line through the grid (PCL's lci): 0 = line inside the surface, 1 = outside, 2 = mixed
// (ratio = fraction of occupied voxels); incnt / pointcount = occupied / visited voxels.
int line_class(const VoxelGrid& grid, int x1, int y1, int z1, int x2, int y2, int z2, float& ratio,
               int& incnt, int& pointcount) {
  int voxelcount = 0, voxel_in = 0;
  int v[3] = {x1, y1, z1};
  const int dx = x2 - x1, dy = y2 - y1, dz = z2 - z1;
  const int x_inc = dx < 0 ? -1 : 1, y_inc = dy < 0 ? -1 : 1, z_inc = dz < 0 ? -1 : 1;
  const int l = std::abs(dx), m = std::abs(dy), n = std::abs(dz);
  const int dx2 = 2 * l, dy2 = 2 * m, dz2 = 2 * n;
  if (l >= m && l >= n) {
    int err_1 = dy2 - l, err_2 = dz2 - l;
    for (int i = 1; i < l; ++i) {
      ++voxelcount;
      voxel_in += grid.at(v[0], v[1], v[2]) ? 1 : 0;
      if (err_1 > 0) { v[1] += y_inc; err_1 -= dx2; }
      if (err_2 > 0) { v[2] += z_inc; err_2 -= dx2; }
      err_1 += dy2;
      err_2 += dz2;
      v[0] += x_inc;
    }
  } else if (m >= l && m >= n) {
    int err_1 = dx2 - m, err_2 = dz2 - m;
    for (int i = 1; i < m; ++i) {
      ++voxelcount;
      voxel_in += grid.at(v[0], v[1], v[2]) ? 1 : 0;
      if (err_1 > 0) { v[0] += x_inc; err_1 -= dy2; }
      if (err_2 > 0) { v[2] += z_inc; err_2 -= dy2; }
      err_1 += dx2;
      err_2 += dz2;
      v[1] += y_inc;
    }
  } else {
    int err_1 = dy2 - n, err_2 = dx2 - n;
    for (int i = 1; i < n; ++i) {
      ++voxelcount;
      voxel_in += grid.at(v[0], v[1], v[2]) ? 1 : 0;
      if (err_1 > 0) { v[1] += y_inc; err_1 -= dz2; }
      if (err_2 > 0) { v[0] += x_inc; err_2 -= dz2; }
      err_1 += dy2;
      err_2 += dx2;
      v[2] += z_inc;
    }
  }
  ++voxelcount;
  voxel_in += grid.at(v[0], v[1], v[2]) ? 1 : 0;
  incnt = voxel_in;
  pointcount = voxelcount;
  if (voxel_in >= voxelcount - 1) return 0;
  if (voxel_in <= 7) return 1;
  ratio = static_cast<float>(voxel_in) / static_cast<float>(voxelcount);
  return 2;
}

size_t uniform_index(std::mt19937_64& rng, size_t n) {
  return static_cast<size_t>((static_cast<unsigned __int128>(rng()) * n) >> 64);
}

// What the triplets give: the A3 sub-histograms and the mixed lines' ratios as they are drawn, and each
// triplet's D2 (three sides) and D3 with their in / out / mixed classes, binned once their largest is known.
struct EsfSamples {
  std::array<float, kBins> h_mix_ratio{}, h_a3_in{}, h_a3_out{}, h_a3_mix{};
  std::vector<float> d2v, d3v, wt_d3;
  std::vector<int> wt_d2;
};

// One triplet's A3, D2 and D3 into `s` (PCL's ESFEstimation); false for a degenerate one (drawn again).
bool add_triplet(const VoxelGrid& grid, const Eigen::Vector3f& p1, const Eigen::Vector3f& p2, const Eigen::Vector3f& p3,
                 EsfSamples& s) {
  const float pih = std::numbers::pi_v<float> / 2.0f;
  // A3: angles of the triangle; D3: square root of its area; D2: side lengths (all from PCL).
  Eigen::Vector3f v21 = p2 - p1, v31 = p3 - p1, v23 = p2 - p3;
  const float a = v21.norm(), b = v31.norm(), cc = v23.norm();
  // Squared area: Heron's s(s-a)(s-b)(s-c) in PCL; the cross product is the same quantity without
  // Heron's cancellation, which lets float-rounded collinear triplets through.
  const float area2 = 0.25f * v21.cross(v31).squaredNorm();
  if (area2 <= 0.001f) return false;
  v21.normalize();
  v31.normalize();
  v23.normalize();
  const float cos1 = std::abs(v21.dot(v31)), cos2 = std::abs(v23.dot(v31)), cos3 = std::abs(v23.dot(v21));
  if (!(cos1 <= 1.0f && cos2 <= 1.0f && cos3 <= 1.0f)) return false;  // acos would be NaN: PCL drops these
  const int th1 = static_cast<int>(pcl_round(std::acos(cos1) / pih * (kBins - 1)));
  const int th2 = static_cast<int>(pcl_round(std::acos(cos2) / pih * (kBins - 1)));
  const int th3 = static_cast<int>(pcl_round(std::acos(cos3) / pih * (kBins - 1)));

  // D2 and the in / out / mixed classification of each side by line tracing in the voxel grid.
  s.d2v.push_back(a);
  s.d2v.push_back(b);
  s.d2v.push_back(cc);
  const Eigen::Vector3f* ends[3][2] = {{&p1, &p2}, {&p1, &p3}, {&p2, &p3}};
  int pcnt[3];
  int vxlcnt_sum = 0, p_cnt = 0;
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3f &from = *ends[e][0], &to = *ends[e][1];
    float ratio = 0;
    int vxlcnt = 0;
    s.wt_d2.push_back(line_class(grid, grid_coord(from.x()), grid_coord(from.y()), grid_coord(from.z()),
                                 grid_coord(to.x()), grid_coord(to.y()), grid_coord(to.z()), ratio, vxlcnt, pcnt[e]));
    if (s.wt_d2.back() == 2) s.h_mix_ratio[static_cast<int>(pcl_round(ratio * (kBins - 1)))]++;
    vxlcnt_sum += vxlcnt;
    p_cnt += pcnt[e];
  }

  s.d3v.push_back(std::sqrt(std::sqrt(area2)));
  std::array<float, kBins>* a3 = nullptr;
  if (vxlcnt_sum <= 21) {
    a3 = &s.h_a3_out;
    s.wt_d3.push_back(0);
  } else if (p_cnt - vxlcnt_sum < 4) {
    a3 = &s.h_a3_in;
    s.wt_d3.push_back(1);
  } else {
    a3 = &s.h_a3_mix;
    s.wt_d3.push_back(static_cast<float>(vxlcnt_sum) / static_cast<float>(p_cnt));
  }
  (*a3)[th1] += static_cast<float>(pcnt[2]) / 32.0f;
  (*a3)[th2] += static_cast<float>(pcnt[0]) / 32.0f;
  (*a3)[th3] += static_cast<float>(pcnt[1]) / 32.0f;
  return true;
}

// The ten sub-histograms from the samples (D2 and D3 binned against their largest), weighted as PCL
// weighs them and normalised to sum 1.
Expected<Eigen::VectorXf> esf_histogram(const EsfSamples& s) {
  std::array<float, kBins> h_in{}, h_out{}, h_mix{}, h_d3_in{}, h_d3_out{}, h_d3_mix{};
  const float maxd2 = *std::max_element(s.d2v.begin(), s.d2v.end());
  const float maxd3 = *std::max_element(s.d3v.begin(), s.d3v.end());
  auto bin = [](float v, float max) { return std::clamp(static_cast<int>(pcl_round(v / max * (kBins - 1))), 0, kBins - 1); };
  for (size_t i = 0; i < s.d3v.size(); ++i) {
    const int index = bin(s.d3v[i], maxd3);
    if (s.wt_d3[i] >= 0.999f) h_d3_in[index]++;
    else if (s.wt_d3[i] <= 0.001f) h_d3_out[index]++;
    else h_d3_mix[index]++;
  }
  for (size_t i = 0; i < s.d2v.size(); ++i) {
    const int index = bin(s.d2v[i], maxd2);
    if (s.wt_d2[i] == 0) h_in[index]++;
    if (s.wt_d2[i] == 1) h_out[index]++;
    if (s.wt_d2[i] == 2) h_mix[index]++;
  }
  const std::array<const std::array<float, kBins>*, 10> parts = {&s.h_a3_in, &s.h_a3_out, &s.h_a3_mix, &h_d3_in, &h_d3_out,
                                                                 &h_d3_mix,   &h_in,       &h_out,       &h_mix,   &s.h_mix_ratio};
  const std::array<float, 10> weights = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 1.0f, 1.0f * 0.5f, 2.0f, 2.0f, 2.0f * 0.5f};
  Eigen::VectorXf h(kEsfSize);
  for (int part = 0; part < 10; ++part)
    for (int i = 0; i < kBins; ++i) h[part * kBins + i] = (*parts[part])[i] * weights[part];
  float sum = 0;
  for (int i = 0; i < kEsfSize; ++i) sum += h[i];  // fixed order, as PCL
  if (!(sum > 0)) return internal_error("esf: empty histogram");
  h /= sum;
  return h;
}

}  // namespace

Expected<Eigen::VectorXf> esf(const Cloud& cloud, uint64_t seed) {
  if (Status s = validate(cloud, "esf"); !s) return s.error();

  // Centre on the centroid and scale into a sphere of radius kHalf voxels (scale_points_unit_sphere).
  const Eigen::Vector3f c = centroid(cloud.points).cast<float>();
  std::vector<Eigen::Vector3f> pts(cloud.points.size());
  float max_distance = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    pts[i] = cloud.points[i] - c;
    max_distance = std::max(max_distance, pts[i].norm());
  }
  const float scale = 1.0f / max_distance * static_cast<float>(kHalf);
  for (Eigen::Vector3f& p : pts) p *= scale;
  VoxelGrid grid;
  voxelize9(pts, grid);

  EsfSamples samples;
  samples.d2v.reserve(3 * kSamples);
  samples.wt_d2.reserve(3 * kSamples);
  samples.d3v.reserve(kSamples);
  samples.wt_d3.reserve(kSamples);
  std::mt19937_64 rng(seed);
  const size_t n = pts.size();
  long draws = 0;
  for (int sample = 0; sample < kSamples;) {
    if (++draws > kMaxDraws) return invalid_argument("esf: degenerate cloud, too few non-collinear point triplets");
    const size_t i1 = uniform_index(rng, n), i2 = uniform_index(rng, n), i3 = uniform_index(rng, n);
    if (i1 == i2 || i1 == i3 || i2 == i3) continue;
    if (add_triplet(grid, pts[i1], pts[i2], pts[i3], samples)) ++sample;
  }
  return esf_histogram(samples);
}

}  // namespace glimpse
