#include "nodes/cloud/principal_extents.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace scallop {

PrincipalExtents principal_extents(const std::vector<Eigen::Vector3d>& P) {
  PrincipalExtents e;
  if (P.size() < 2) return e;
  // Relative to the first point: sums stay well-conditioned for a part far from the origin.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : P) mean += p - P[0];
  mean = P[0] + mean / static_cast<double>(P.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : P) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);  // eigenvalues ascending
  const Eigen::Matrix3d axes = es.eigenvectors();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : P) {
    const Eigen::Vector3d q = axes.transpose() * (p - mean);
    lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  const Eigen::Vector3d range = hi - lo;
  e.length = range[2], e.width = range[1], e.thickness = range[0];
  e.axis = axes.col(2).normalized();
  return e;
}

bool one_dimensional(const PrincipalExtents& e, double spacing) {
  return e.length > 0 && (e.width < spacing || e.width < 1e-3 * e.length);
}

double median_spacing(const Neighborhoods& nbrs) {
  std::vector<double> d;
  d.reserve(nbrs.size());
  for (std::size_t i = 0; i < nbrs.size(); ++i)
    for (int j = 0; j < nbrs.k; ++j)
      if (nbrs.sq_dist(i, j) > 0) {
        d.push_back(std::sqrt(nbrs.sq_dist(i, j)));
        break;
      }
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

std::string one_dimensional_problem(const PrincipalExtents& e, double spacing) {
  if (!one_dimensional(e, spacing)) return "";
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "the cloud is one-dimensional: its points lie along a line %.3g mm long and %.3g mm wide (points "
                "%.3g mm apart), not on a surface; scallop machines surface patches",
                e.length, e.width, spacing);
  return buf;
}

}  // namespace scallop
