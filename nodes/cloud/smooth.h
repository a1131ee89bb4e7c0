// Laplacian fairing of a noisy cloud along its normals.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace scallop {

// P   #P by 3 positions (mm);  N  #P by 3 unit normals
// L   #P by #P meshless Laplacian (build_laplacian; rows normalised so (L P)_i is the
//     displacement of p_i from the weighted mean of its neighbours, in mm)
// is_boundary  #P flags, or empty: flagged points are kept where they are (their one-sided
//     neighbourhood would pull them inwards)
// iterations >= 0, lambda in (0, 1]
// Each iteration moves every other point along its normal only (tangential drift would change the
// sampling, not the surface): p_i <- p_i - lambda ((L p)_i . n_i) n_i, with L fixed.
// Returns the moved positions; the normals are left as they are.
// Throws std::invalid_argument for mismatched sizes or parameters out of range.
std::vector<Eigen::Vector3d> smooth_cloud(const std::vector<Eigen::Vector3d>& P,
                                          const std::vector<Eigen::Vector3d>& N,
                                          const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                                          const std::vector<std::uint8_t>& is_boundary, int iterations,
                                          double lambda);

}  // namespace scallop
