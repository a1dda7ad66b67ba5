#include "glimpse/geometry/surface_fit.h"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>

#include "glimpse/geometry/normal_orientation.h"
#include "glimpse/threads.h"

namespace glimpse {

float support_radius(const NeighbourIndex& tree, const SurfaceParams& params) {
  return estimate_density(tree, params.support_radius_m, params.support_neighbours).support_radius_m;
}

Eigen::Vector2f harris_matrix_eigenvalues(double p1, double p2, double p3, double p4, double p5, double sigma) {
  const double s2 = sigma * sigma;
  const double A = p4 * p4 + s2 * (p1 * p1 + p2 * p2);
  const double B = p5 * p5 + s2 * (p2 * p2 + p3 * p3);
  const double C = p4 * p5 + s2 * (p1 * p2 + p2 * p3);
  const double mean = 0.5 * (A + B);
  const double dev = std::sqrt(0.25 * (A - B) * (A - B) + C * C);
  return {static_cast<float>(std::max(0.0, mean - dev)), static_cast<float>(mean + dev)};
}

Eigen::Vector2f harris_eigenvalues(float p1, float p2, float p3, float p4, float p5) {
  // Sipiran & Bustos 2011's closed form, the quadric in metres: sigma^2 = 2 m^2.
  return harris_matrix_eigenvalues(p1, p2, p3, p4, p5, std::numbers::sqrt2);
}

Eigen::Vector2f principal_curvatures(float p1, float p2, float p3, float p4, float p5) {
  // First and second fundamental forms of the graph z = f(x, y) at the origin: E, F, G and
  // (L, M, N) = (p1, p2, p3) / w with w^2 = 1 + fx^2 + fy^2 = EG - F^2.
  const double fx = p4, fy = p5;
  const double E = 1 + fx * fx, F = fx * fy, G = 1 + fy * fy;
  const double inv_w2 = 1 / (1 + fx * fx + fy * fy), inv_w = std::sqrt(inv_w2);
  const double K = (double(p1) * p3 - double(p2) * p2) * inv_w2 * inv_w2;
  const double H = 0.5 * (E * p3 - 2 * F * p2 + G * p1) * inv_w2 * inv_w;
  const double root = std::sqrt(std::max(0.0, H * H - K));
  return {static_cast<float>(H + root), static_cast<float>(H - root)};
}

namespace {

// exp(-2 s) for s in [0, 1], a neighbour's squared distance in units of r: (e^(-s/4))^8 with e^(-s/4)
// from its degree-5 Taylor polynomial (relative error < 3e-6). Inline, so the weight loop vectorises.
inline float gaussian_weight(float s) {
  const float t = -0.25f * s;
  float e = 1.f + t * (1.f + t * (0.5f + t * (1.f / 6 + t * (1.f / 24 + t * (1.f / 120)))));
  e *= e;
  e *= e;
  return e * e;
}

// Solves the 6x6 symmetric positive definite normal equations A c = b (lower triangle of A, row by
// row; unknowns: three quadratic, then two linear and the constant coefficient) by blocks: with
// A = [Q B; B^T P], the Schur complement S = Q - B P^-1 B^T gives the quadratic part, then the rest.
// Two 3x3 inverses by cofactors: few divisions, so little waiting on them. False when a block is
// (nearly) singular, for the caller's pivoting fallback.
bool solve_normal_equations6(const double (&lower)[21], const double (&b)[6], double (&c)[6]) {
  auto a = [&](int i, int j) { return i >= j ? lower[i * (i + 1) / 2 + j] : lower[j * (j + 1) / 2 + i]; };
  Eigen::Matrix3d Q, B, P;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Q(i, j) = a(i, j), B(i, j) = a(i, j + 3), P(i, j) = a(i + 3, j + 3);
  const Eigen::Vector3d bq(b[0], b[1], b[2]), bl(b[3], b[4], b[5]);
  auto well_posed = [](const Eigen::Matrix3d& M, double det) {
    return det > 1e-12 * M(0, 0) * M(1, 1) * M(2, 2) && det > 0;
  };
  const double det_p = P.determinant();
  if (!well_posed(P, det_p)) return false;
  const Eigen::Matrix3d P_inv = P.inverse();
  const Eigen::Matrix3d BP = B * P_inv;
  const Eigen::Matrix3d S = Q - BP * B.transpose();
  const double det_s = S.determinant();
  if (!well_posed(S, det_s)) return false;
  const Eigen::Vector3d cq = S.inverse() * (bq - BP * bl);
  const Eigen::Vector3d cl = P_inv * (bl - B.transpose() * cq);
  for (int i = 0; i < 3; ++i) c[i] = cq[i], c[i + 3] = cl[i];
  return true;
}

// Unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3x3 matrix: the
// smallest root of the characteristic polynomial by Newton's method from 0 (the cubic is concave and
// increasing there, so the iterates climb monotonically to it), then the largest cross product of
// two rows of C - lambda I. Falls back to Eigen's solver when the root is (nearly) double.
bool smallest_eigenvector(const Eigen::Matrix3d& C, Eigen::Vector3d& v) {
  const double a = C.trace();
  const double b = C(0, 0) * C(1, 1) + C(0, 0) * C(2, 2) + C(1, 1) * C(2, 2) - C(0, 1) * C(0, 1) -
                   C(0, 2) * C(0, 2) - C(1, 2) * C(1, 2);
  const double c = C.determinant();
  bool converged = false;
  double lambda = 0;
  if (a > 0) {
    for (int it = 0; it < 32; ++it) {
      const double f = ((lambda - a) * lambda + b) * lambda - c;
      const double df = (3 * lambda - 2 * a) * lambda + b;
      if (!(df > 0)) break;
      const double step = f / df;
      lambda -= step;
      if (std::abs(step) <= 1e-11 * a) {
        converged = true;
        break;
      }
    }
  }
  if (converged) {
    const Eigen::Matrix3d M = C - lambda * Eigen::Matrix3d::Identity();
    const Eigen::Vector3d c01 = M.row(0).cross(M.row(1)), c02 = M.row(0).cross(M.row(2)),
                          c12 = M.row(1).cross(M.row(2));
    const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
    const Eigen::Vector3d& best = n01 >= n02 ? (n01 >= n12 ? c01 : c12) : (n02 >= n12 ? c02 : c12);
    const double nb = std::max({n01, n02, n12});
    if (nb > 1e-16 * a * a * a * a) {
      v = best / std::sqrt(nb);
      return v.allFinite();
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(C);
  if (es.info() != Eigen::Success || !es.eigenvectors().allFinite()) return false;
  v = es.eigenvectors().col(0).normalized();
  return v.allFinite();
}

}  // namespace

Vec3 pca_normal(const NeighbourIndex& tree, const Vec3& centre, float radius, std::vector<Neighbour>& scratch) {
  tree.radius(centre, radius, scratch);
  if (scratch.size() < 3) return Vec3::Zero();
  const Points& pts = tree.points();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Neighbour& n : scratch) c += pts[n.index].cast<double>();
  c /= static_cast<double>(scratch.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Neighbour& n : scratch) {
    const Eigen::Vector3d d = pts[n.index].cast<double>() - c;
    cov.noalias() += d * d.transpose();
  }
  Eigen::Vector3d normal;
  if (!smallest_eigenvector(cov, normal)) return Vec3::Zero();
  return normal.cast<float>();
}

namespace {

// A neighbourhood as the fit reads it: coordinates relative to the point, divided by r, so every value
// lies in [-1, 1], single-precision sums lose nothing the fit can resolve, and the normal equations stay
// well conditioned. Structure of arrays (x, y, z, weight), so the moment loops vectorise; one buffer per
// thread, grown when needed and reused from point to point. Arrays are padded to a multiple of 4 with
// zero points of zero weight, which add nothing to any sum, so the vector loops need no scalar remainder.
struct ScaledNeighbourhood {
  float *X, *Y, *Z, *W;
  int m = 0, padded = 0;
};
ScaledNeighbourhood scaled_neighbourhood(const Points& pts, const Vec3& p, const std::vector<Neighbour>& nb, float inv_r) {
  thread_local std::vector<float> buffer;
  ScaledNeighbourhood h;
  h.m = static_cast<int>(nb.size());
  h.padded = (h.m + 3) & ~3;
  if (buffer.size() < 4 * static_cast<size_t>(h.padded)) buffer.resize(4 * static_cast<size_t>(h.padded));
  h.X = buffer.data();
  h.Y = h.X + h.padded;
  h.Z = h.Y + h.padded;
  h.W = h.Z + h.padded;
  for (int i = 0; i < h.m; ++i) {
    const Vec3 d = (pts[nb[i].index] - p) * inv_r;
    h.X[i] = d.x(), h.Y[i] = d.y(), h.Z[i] = d.z();
  }
  for (int i = h.m; i < h.padded; ++i) h.X[i] = h.Y[i] = h.Z[i] = 0;
  return h;
}

// PCA's normal of the neighbourhood (first and second moments in one pass, covariance = E[dd^T] -
// E[d]E[d]^T); false when the points do not spread in two directions: the sum of the principal 2x2
// minors is l1 l2 + l1 l3 + l2 l3, about l1 l2 on a surface and ~0 when the points lie on a line
// (l2/l1 < 1e-6, a spread across the line under 1/1000 of the spread along it), where no quadric is
// determined.
bool pca_normal(const ScaledNeighbourhood& h, Eigen::Vector3d& n) {
  const float *X = h.X, *Y = h.Y, *Z = h.Z;
  float sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
#pragma omp simd reduction(+ : sx, sy, sz, sxx, sxy, sxz, syy, syz, szz)
  for (int i = 0; i < h.padded; ++i) {
    sx += X[i], sy += Y[i], sz += Z[i];
    sxx += X[i] * X[i], sxy += X[i] * Y[i], sxz += X[i] * Z[i];
    syy += Y[i] * Y[i], syz += Y[i] * Z[i], szz += Z[i] * Z[i];
  }
  const double inv_m = 1.0 / h.m;
  const Eigen::Vector3d mean = Eigen::Vector3d(sx, sy, sz) * inv_m;
  Eigen::Matrix3d cov;
  cov << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  cov = cov * inv_m - mean * mean.transpose();
  const double minors = cov(0, 0) * cov(1, 1) + cov(0, 0) * cov(2, 2) + cov(1, 1) * cov(2, 2) -
                        cov(0, 1) * cov(0, 1) - cov(0, 2) * cov(0, 2) - cov(1, 2) * cov(1, 2);
  if (!(minors > 1e-6 * cov.trace() * cov.trace())) return false;
  return smallest_eigenvector(cov, n);
}

// Eq. 1: least squares for z = 1/2 p1 x^2 + p2 xy + 1/2 p3 y^2 + p4 x + p5 y + p6 in the frame (e1, e2, n)
// centred on the point (coefficients c in units of r). Gaussian weights (sigma = r/2) favour the centre,
// so a crease at the edge of the neighbourhood bends the fit less (fewer false corners next to sharp
// edges). The normal equations need only the weighted moments sum w x^a y^b (a + b <= 4) and
// sum w z x^a y^b (a + b <= 2). Rewrites the neighbourhood in place: X, Y, Z become the frame
// coordinates, W the weights. False when the fit is not finite.
bool quadric_fit(ScaledNeighbourhood& h, const Eigen::Vector3d& n, double (&c)[6]) {
  // Any tangent frame will do: the curvatures and Harris eigenvalues of the fit do not depend on
  // how the frame is turned about the normal (the quadric basis is complete in x, y).
  const Eigen::Vector3d e1 = n.unitOrthogonal();
  const Eigen::Vector3d e2 = n.cross(e1);
  const float e1x = float(e1.x()), e1y = float(e1.y()), e1z = float(e1.z());
  const float e2x = float(e2.x()), e2y = float(e2.y()), e2z = float(e2.z());
  const float nx = float(n.x()), ny = float(n.y()), nz = float(n.z());
  float *X = h.X, *Y = h.Y, *Z = h.Z, *W = h.W;
#pragma omp simd
  for (int i = 0; i < h.padded; ++i) {
    const float x = X[i] * e1x + Y[i] * e1y + Z[i] * e1z;
    const float y = X[i] * e2x + Y[i] * e2y + Z[i] * e2z;
    const float z = X[i] * nx + Y[i] * ny + Z[i] * nz;
    W[i] = gaussian_weight(X[i] * X[i] + Y[i] * Y[i] + Z[i] * Z[i]);
    X[i] = x, Y[i] = y, Z[i] = z;
  }
  for (int i = h.m; i < h.padded; ++i) W[i] = 0;
  float m00 = 0, m10 = 0, m01 = 0, m20 = 0, m11 = 0, m02 = 0, m30 = 0, m21 = 0, m12 = 0, m03 = 0;
  float m40 = 0, m31 = 0, m22 = 0, m13 = 0, m04 = 0;
#pragma omp simd reduction(+ : m00, m10, m01, m20, m11, m02, m30, m21, m12, m03, m40, m31, m22, m13, m04)
  for (int i = 0; i < h.padded; ++i) {
    const float x = X[i], y = Y[i], w = W[i];
    const float wx = w * x, wy = w * y, wxx = wx * x, wxy = wx * y, wyy = wy * y;
    m00 += w, m10 += wx, m01 += wy, m20 += wxx, m11 += wxy, m02 += wyy;
    m30 += wxx * x, m21 += wxx * y, m12 += wyy * x, m03 += wyy * y;
    m40 += wxx * x * x, m31 += wxx * x * y, m22 += wxx * y * y, m13 += wyy * x * y, m04 += wyy * y * y;
  }
  float z00 = 0, z10 = 0, z01 = 0, z20 = 0, z11 = 0, z02 = 0;
#pragma omp simd reduction(+ : z00, z10, z01, z20, z11, z02)
  for (int i = 0; i < h.padded; ++i) {
    const float x = X[i], y = Y[i], wz = W[i] * Z[i];
    z00 += wz, z10 += wz * x, z01 += wz * y, z20 += wz * x * x, z11 += wz * x * y, z02 += wz * y * y;
  }
  // Rows (x^2/2, xy, y^2/2, x, y, 1): the lower triangle of A^T W A, and A^T W z.
  const double lower[21] = {m40 / 4.0,
                            m31 / 2.0, m22,
                            m22 / 4.0, m13 / 2.0, m04 / 4.0,
                            m30 / 2.0, m21, m12 / 2.0, m20,
                            m21 / 2.0, m12, m03 / 2.0, m11, m02,
                            m20 / 2.0, m11, m02 / 2.0, m10, m01, m00};
  const double atz[6] = {z20 / 2.0, z11, z02 / 2.0, z10, z01, z00};
  if (!solve_normal_equations6(lower, atz, c)) {
    // Degenerate (e.g. nearly collinear) neighbourhood, a block not clearly invertible: Eigen's
    // pivoting LDLT copes with it.
    Eigen::Matrix<double, 6, 6> AtA;
    Eigen::Matrix<double, 6, 1> Atz;
    for (int a = 0, k = 0; a < 6; ++a) {
      Atz[a] = atz[a];
      for (int b = 0; b <= a; ++b) AtA(a, b) = AtA(b, a) = lower[k++];
    }
    const Eigen::Matrix<double, 6, 1> sol = AtA.ldlt().solve(Atz);
    for (int a = 0; a < 6; ++a) c[a] = sol[a];
  }
  for (int a = 0; a < 6; ++a)
    if (!std::isfinite(c[a])) return false;
  return true;
}

}  // namespace

LocalSurface local_surface(const NeighbourIndex& tree, uint32_t index, float r,
                           const std::optional<Vec3>& viewpoint, int min_neighbours,
                           std::vector<Neighbour>& nb) {
  LocalSurface s;
  const Points& pts = tree.points();
  const Vec3& p = pts[index];
  tree.radius(p, r, nb);
  s.neighbours = static_cast<uint16_t>(std::min<size_t>(nb.size(), 65535));
  if (static_cast<int>(nb.size()) < std::max(min_neighbours, 6)) return s;
  const float inv_r = 1.f / r;
  ScaledNeighbourhood h = scaled_neighbourhood(pts, p, nb, inv_r);
  Eigen::Vector3d n;
  if (!pca_normal(h, n)) return s;
  if (viewpoint && n.dot((*viewpoint - p).cast<double>()) < 0) n = -n;
  double c[6];
  if (!quadric_fit(h, n, c)) return s;
  // Undo the 1/r scaling: second-order terms scale with 1/r, slopes are unitless.
  const float p1 = static_cast<float>(c[0] * inv_r), p2 = static_cast<float>(c[1] * inv_r),
              p3 = static_cast<float>(c[2] * inv_r), p4 = static_cast<float>(c[3]),
              p5 = static_cast<float>(c[4]);
  const Eigen::Vector2f k = principal_curvatures(p1, p2, p3, p4, p5);
  const Eigen::Vector2f lambda = harris_eigenvalues(p1, p2, p3, p4, p5);  // eq. 2
  // The Harris response over the fit's own window (sigma = r/2): in units of r, sigma = 1/2.
  const Eigen::Vector2f e = harris_matrix_eigenvalues(c[0], c[1], c[2], c[3], c[4], 0.5);
  s.harris_response = static_cast<float>(harris_response(e[0], e[1]));
  s.normal = n.cast<float>();
  s.k1 = k[0];
  s.k2 = k[1];
  s.lambda_min = lambda[0];
  s.lambda_max = lambda[1];
  s.valid = s.normal.allFinite() && std::isfinite(s.lambda_max);
  return s;
}

std::vector<LocalSurface> local_surfaces(const NeighbourIndex& tree, float r, const std::optional<Vec3>& viewpoint,
                                         const SurfaceParams& params, const CancelFn& cancel) {
  const size_t n = tree.points().size();
  std::vector<LocalSurface> out(n);
  const int threads = resolve_threads(params.threads);
  std::atomic<bool> stop = false;
#pragma omp parallel num_threads(threads)
  {
    std::vector<Neighbour> scratch;
#pragma omp for schedule(dynamic, 256)
    for (int64_t i = 0; i < static_cast<int64_t>(n); ++i) {
      if (i % 256 == 0 && cancel && cancel()) stop = true;
      if (stop) continue;
      out[i] = local_surface(tree, static_cast<uint32_t>(i), r, viewpoint, params.min_neighbours, scratch);
    }
  }
  if (stop) return out;
  if (!viewpoint) orient_normals_propagated(tree, out);
  return out;
}

}  // namespace glimpse
