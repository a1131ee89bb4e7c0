#include "nodes/cloud/smooth.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>
#include <string>

namespace scallop {

std::vector<Eigen::Vector3d> smooth_cloud(const std::vector<Eigen::Vector3d>& P,
                                          const std::vector<Eigen::Vector3d>& N,
                                          const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                                          const std::vector<std::uint8_t>& is_boundary, int iterations,
                                          double lambda) {
  const std::size_t n = P.size();
  if (N.size() != n)
    throw std::invalid_argument("smoothing needs normals (the cloud has " + std::to_string(N.size()) +
                                " normals for " + std::to_string(n) + " points)");
  if (static_cast<std::size_t>(L.rows()) != n || static_cast<std::size_t>(L.cols()) != n)
    throw std::invalid_argument("the Laplacian is " + std::to_string(L.rows()) + " by " + std::to_string(L.cols()) +
                                " but the cloud has " + std::to_string(n) + " points");
  if (!is_boundary.empty() && is_boundary.size() != n)
    throw std::invalid_argument("the boundary flags are for " + std::to_string(is_boundary.size()) +
                                " points but the cloud has " + std::to_string(n));
  if (iterations < 0) throw std::invalid_argument("iterations must be >= 0");
  if (!(lambda > 0 && lambda <= 1)) throw std::invalid_argument("lambda must be in (0, 1]");

  std::vector<Eigen::Vector3d> cur(P), next(n);
  for (int it = 0; it < iterations; ++it) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        if (!is_boundary.empty() && is_boundary[i]) {
          next[i] = cur[i];
          continue;
        }
        Eigen::Vector3d lp = Eigen::Vector3d::Zero();
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator e(L, static_cast<Eigen::Index>(i)); e; ++e)
          lp += e.value() * cur[e.col()];
        next[i] = cur[i] - lambda * lp.dot(N[i]) * N[i];
      }
    });
    cur.swap(next);
  }
  return cur;
}

}  // namespace scallop
