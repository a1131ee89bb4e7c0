#include "nodes/param/planar_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace scallop {

UVMap planar_map(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer, double angle) {
  if (P.size() < 3) throw std::invalid_argument("a planar map needs at least 3 points (got " + std::to_string(P.size()) + ")");
  if (outer.size() < 3)
    throw std::invalid_argument("the outer loop has " + std::to_string(outer.size()) + " points; it needs at least 3");
  for (int i : outer)
    if (i < 0 || static_cast<std::size_t>(i) >= P.size())
      throw std::invalid_argument("the outer loop names point " + std::to_string(i) + "; the cloud has " +
                                  std::to_string(P.size()));
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!P[i].allFinite()) throw std::invalid_argument("point " + std::to_string(i) + " has a NaN or infinite coordinate");
    mean += P[i].head<2>();
  }
  mean /= double(P.size());
  // The passes' direction d (unit, in xy): v runs along it, u across.
  Eigen::Vector2d d;
  if (angle >= 0) {
    const double a = angle * std::numbers::pi / 180;
    d = {std::cos(a), std::sin(a)};
  } else {
    Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
    for (const auto& p : P) C += (p.head<2>() - mean) * (p.head<2>() - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(C);
    d = eig.eigenvectors().col(0);  // the lesser extent: the passes run the short way
    if (d.x() < 0 || (d.x() == 0 && d.y() < 0)) d = -d;  // one of the two, always the same
  }
  const Eigen::Vector2d across(d.y(), -d.x());  // u: (u, v) keeps the orientation of (x, y)
  UVMap m;
  m.domain = "planar";
  m.uv.resize(P.size());
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Eigen::Vector2d q = P[i].head<2>() - mean;
    m.uv[i] = {across.dot(q), d.dot(q)};
    lo = lo.cwiseMin(m.uv[i]);
    hi = hi.cwiseMax(m.uv[i]);
  }
  for (auto& q : m.uv) q -= lo;
  m.width = hi.x() - lo.x();
  m.height = hi.y() - lo.y();
  if (!(m.width > 0 && m.height > 0))
    throw std::invalid_argument("the points span no area in xy (" + std::to_string(m.width) + " by " +
                                std::to_string(m.height) + " mm): not a patch seen from +z");
  m.outer_loop = outer;
  for (int i : outer) m.boundary_uv.push_back(m.uv[i]);
  return m;
}

}  // namespace scallop
