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
// The heat-kernel time build_laplacian uses for a given t: t itself when positive, else
// mean_sq_neighbor_distance (1 where every point coincides).
double heat_time(const Neighborhoods& nbrs, double t);

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

// L with the rows of `points` rebuilt by `scheme` (t, regularization as build_laplacian's; t > 0)
// over their neighbours both ways: the points a row names and the points whose rows name it. A
// region whose points all have their k nearest neighbours inside it (a denser patch beside a
// sparser one, as a scan's overlapping strips leave) is reached by its surroundings' rows but
// reaches nothing outside through its own, so the harmonic system is singular there; rebuilt
// this way each of its rows names the points around it that name it, with the scheme's
// precision (optimal: linear). Rows of other points are unchanged. P, N as build_laplacian's.
// Throws std::invalid_argument for mismatched sizes or a point index outside L.
Eigen::SparseMatrix<double, Eigen::RowMajor> join_rows_both_ways(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                                                                 const std::vector<Eigen::Vector3d>& P,
                                                                 const std::vector<Eigen::Vector3d>& N,
                                                                 LaplacianScheme scheme, double t, double regularization,
                                                                 const std::vector<int>& points);

}  // namespace scallop
