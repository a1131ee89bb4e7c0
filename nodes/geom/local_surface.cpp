#include "nodes/geom/local_surface.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>

namespace scallop {

std::optional<LocalSurface> fit_local_surface(const std::vector<Eigen::Vector3d>& pts) {
  if (pts.size() < kMinSurfacePoints) return std::nullopt;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= double(pts.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) C += (p - c) * (p - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  // Not a plane where the points lie along a line, or where their spread across the plane is
  // not well above their spread off it: a thin band of a curved face has its least-squares plane
  // through its arc, its normal about the surface's tangent (seen on a sphere: 80 degrees off).
  const Eigen::Vector3d& ev = es.eigenvalues();
  if (es.info() != Eigen::Success || !(ev[1] > 1e-6 * ev[2]) || !(ev[0] <= 0.25 * ev[1])) return std::nullopt;
  LocalSurface plane{es.eigenvectors().col(0), c, es.eigenvectors().col(2), es.eigenvectors().col(1)};
  Eigen::MatrixXd A(pts.size(), 6);
  Eigen::VectorXd w(pts.size());
  double scale = 0;
  for (const auto& p : pts) scale = std::max(scale, (p - c).norm());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d d = pts[i] - c;
    const double u = d.dot(plane.t1) / scale, v = d.dot(plane.t2) / scale;
    A.row(i) << 1, u, v, u * u, u * v, v * v;
    w[i] = d.dot(plane.normal);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (sv[5] > 1e-3 * sv[0]) {
    const Eigen::VectorXd q = svd.solve(w);
    const double k[6] = {1, 1 / scale, 1 / scale, 1 / (scale * scale), 1 / (scale * scale), 1 / (scale * scale)};
    for (int j = 0; j < 6; ++j) plane.c[j] = q[j] * k[j];
  }
  return plane;
}

}  // namespace scallop
