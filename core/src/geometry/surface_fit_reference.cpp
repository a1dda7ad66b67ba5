// The plain fit of a local surface, the specification local_surface (surface_fit.cpp) is tested equal to.
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "glimpse/geometry/surface_fit.h"

namespace glimpse {

LocalSurface reference_local_surface(const Points& pts, uint32_t index, float r, const Vec3& viewpoint,
                                     int min_neighbours) {
  LocalSurface s;
  std::vector<uint32_t> nb;
  for (uint32_t j = 0; j < pts.size(); ++j)
    if ((pts[j] - pts[index]).squaredNorm() <= r * r) nb.push_back(j);
  if (nb.size() < static_cast<size_t>(std::max(3, min_neighbours))) return s;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (uint32_t j : nb) c += pts[j].cast<double>();
  c /= static_cast<double>(nb.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t j : nb) cov += (pts[j].cast<double>() - c) * (pts[j].cast<double>() - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  // Neighbours on a line (l2 / l1 <= 1e-6) determine no surface.
  const Eigen::Vector3d l = es.eigenvalues();
  if (!(l[2] * l[1] + l[2] * l[0] + l[1] * l[0] > 1e-6 * cov.trace() * cov.trace())) return s;
  Eigen::Vector3d n = es.eigenvectors().col(0);
  const Eigen::Vector3d p = pts[index].cast<double>();
  if (n.dot(viewpoint.cast<double>() - p) < 0) n = -n;
  const Eigen::Vector3d e1 = es.eigenvectors().col(2), e2 = n.cross(e1);
  Eigen::MatrixXd A(nb.size(), 6);
  Eigen::VectorXd z(nb.size());
  for (size_t k = 0; k < nb.size(); ++k) {
    const Eigen::Vector3d d = (pts[nb[k]].cast<double>() - p) / r;
    const double x = d.dot(e1), y = d.dot(e2), sw = std::sqrt(std::exp(-2 * d.squaredNorm()));
    A.row(static_cast<Eigen::Index>(k)) << 0.5 * x * x, x * y, 0.5 * y * y, x, y, 1;
    A.row(static_cast<Eigen::Index>(k)) *= sw;
    z[static_cast<Eigen::Index>(k)] = sw * d.dot(n);
  }
  const Eigen::VectorXd q = A.colPivHouseholderQr().solve(z);
  const float p1 = float(q[0] / r), p2 = float(q[1] / r), p3 = float(q[2] / r), p4 = float(q[3]), p5 = float(q[4]);
  const Eigen::Vector2f k = principal_curvatures(p1, p2, p3, p4, p5);
  const Eigen::Vector2f h = harris_eigenvalues(p1, p2, p3, p4, p5);
  s.normal = n.cast<float>();
  s.k1 = k[0], s.k2 = k[1], s.lambda_min = h[0], s.lambda_max = h[1];
  const Eigen::Vector2f e = harris_matrix_eigenvalues(q[0], q[1], q[2], q[3], q[4], 0.5);  // sigma = r/2
  s.harris_response = static_cast<float>(harris_response(e[0], e[1]));
  s.valid = true;
  // Where the two smallest PCA axes nearly tie the normal is ill-defined: callers skip such points.
  s.neighbours = (es.eigenvalues()[1] - es.eigenvalues()[0]) > 1e-3 * es.eigenvalues()[2] ? 1 : 0;
  return s;
}

}  // namespace glimpse
