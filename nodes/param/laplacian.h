// Meshless Laplacian of a point cloud on its KNN graph (paper: "Iso-parametric tool-path
// planning for point clouds", section 2.1): (L f)_i = sum_j w_ij (f_i - f_j) over the k nearest
// neighbours j of i.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <string>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

enum class LaplacianScheme {
  Uniform,  // graph Laplacian: w_ij = 1
  Heat,     // Belkin & Niyogi heat kernel: w_ij = exp(-|p_i - p_j|^2 / t)
  Optimal   // Schmidt & Singh optimal weights (the paper's preferred scheme)
};

// "uniform", "heat", "optimal"; throws std::invalid_argument otherwise.
LaplacianScheme parse_laplacian_scheme(const std::string& name);
std::string to_string(LaplacianScheme scheme);

// Automatic heat-kernel time: the mean squared neighbour distance over all KNN pairs (mm^2).
double mean_sq_neighbor_distance(const Neighborhoods& nbrs);

// P     #P by 3 positions (mm)
// N     #P by 3 unit normals, or empty: the optimal scheme then uses local PCA normals of the
//       point and its neighbours (the other schemes never need normals)
// nbrs  k neighbours per point (self excluded); optimal needs k >= 3
// t     heat time (mm^2); <= 0 means mean_sq_neighbor_distance(nbrs)
// regularization  delta of the optimal scheme's system (C + delta trace(C) I) w = 1
// Returns L, #P by #P, row-major, with k+1 entries per row: L_ii = 1, L_ij = -w_ij, where each
// row's weights are normalised to sum 1 (random-walk form: (L f)_i = f_i - weighted mean of f
// over the neighbours). Rows sum to zero. Row scaling does not change the harmonic map, and the
// normalised form makes (L p)_i a displacement in mm, as cloud.smooth needs.
//
// Optimal weights (Schmidt & Singh, paper eq. for C W = 1): with d_j = p_i - p_j' (p_j' the
// projection of p_j on the tangent plane at p_i), c_jk = d_j . d_k. C has rank <= 2, so we solve
// (C + delta trace(C) I) w = 1, rescale to sum 1, then project w (least change) onto the exact
// constraints sum_j w_j d_j = 0, sum_j w_j = 1. The projection gives linear precision: on a
// plane, sum_j w_ij p_j = p_i exactly, so affine functions are harmonic. It is skipped when the
// neighbours are (nearly) collinear in the tangent plane.
// progress: optional, called with the fraction of the rows done, in [0, 1].
// Throws std::invalid_argument for mismatched sizes, k too small, bad indices, non-finite
// positions or a non-positive regularization.
Eigen::SparseMatrix<double, Eigen::RowMajor> build_laplacian(const std::vector<Eigen::Vector3d>& P,
                                                             const std::vector<Eigen::Vector3d>& N,
                                                             const Neighborhoods& nbrs,
                                                             LaplacianScheme scheme, double t = 0,
                                                             double regularization = 1e-3,
                                                             const std::function<void(double)>& progress = {});

}  // namespace scallop
