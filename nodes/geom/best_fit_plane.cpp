#include "nodes/geom/best_fit_plane.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace scallop {

void best_fit_plane(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                    Eigen::Vector3d& c, Eigen::Vector3d& n) {
  c.setZero();
  for (const auto& p : P) c += p;
  c /= static_cast<double>(std::max<std::size_t>(P.size(), 1));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : P) cov += (p - c) * (p - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  n = es.eigenvectors().col(0).normalized();
  Eigen::Vector3d ref = Eigen::Vector3d::UnitZ();
  if (!N.empty()) {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (const auto& x : N) s += x;
    if (s.norm() > 0) ref = s;
  }
  if (n.dot(ref) < 0) n = -n;
}

}  // namespace scallop
