// Harmonic map of a point cloud with its outer boundary fixed (paper section 2.1, eq. (1)):
// L f = 0 at every point not on the outer loop, f = boundary map on the outer loop; solved once
// for u and once for v with one factorisation.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <utility>
#include <vector>

#include "nodes/types/param.h"

namespace scallop {

enum class HarmonicSolver {
  Direct,    // UMFPACK sparse LU (the matrix is not symmetric)
  BiCGSTAB,  // Eigen BiCGSTAB, incomplete-LUT preconditioner
  GMRES      // Eigen (unsupported) restarted GMRES, incomplete-LUT preconditioner
};

// "direct", "bicgstab", "gmres"; throws std::invalid_argument otherwise.
HarmonicSolver parse_harmonic_solver(const std::string& name);

// L         #P by #P meshless Laplacian (build_laplacian)
// boundary  a UVMap from map_boundary: outer_loop and boundary_uv are used, the rest copied
// Returns the map with uv (#P) filled and residual = ||A X - B||_F / ||B||_F of the interior
// system A X = B (X #interior by 2). Every point not on the outer loop is an unknown with its own
// Laplace row; points of inner loops (holes) are thereby free, natural boundaries: in the
// meshless setting their one-sided neighbourhood row is the natural-boundary discretisation.
// Outer-loop points keep boundary_uv exactly.
// fixed     Dirichlet values (point index, uv) of further points, or replacing boundary_uv of
//           outer-loop points (outer_band_values gives both for the whole boundary band); these
//           points keep their uv exactly. The returned boundary_uv holds the values used.
// Throws std::invalid_argument for mismatched sizes, and std::runtime_error when the solve fails
// (singular system: points not connected to the outer loop through neighbours) or its relative
// residual exceeds 1e-6.
UVMap solve_harmonic(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L, const UVMap& boundary,
                     HarmonicSolver solver = HarmonicSolver::Direct,
                     const std::vector<std::pair<int, Eigen::Vector2d>>& fixed = {});

}  // namespace scallop
