// Harmonic map of a point cloud with its outer boundary fixed (paper section 2.1, eq. (1)):
// L f = 0 at every point not on the outer loop, f = boundary map on the outer loop; solved once
// for u and once for v with one factorisation.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "nodes/types/param.h"

namespace scallop {

enum class HarmonicSolver {
  TwoLevel,  // from 50 000 unknowns: GMRES with a two-level preconditioner (two_level_solver.h):
             // Gauss-Seidel and an UMFPACK LU of the system summed over aggregates of neighbours;
             // below that, and when it does not converge, UMFPACK on the whole system (Direct)
  Direct,    // UMFPACK sparse LU (the matrix is not symmetric)
  BiCGSTAB,  // Eigen BiCGSTAB, incomplete-LUT preconditioner
  GMRES      // Eigen (unsupported) restarted GMRES, incomplete-LUT preconditioner
};

// Given the points whose rows lead nowhere, L with those rows rebuilt (see solve_harmonic).
using JoinRows = std::function<Eigen::SparseMatrix<double, Eigen::RowMajor>(const std::vector<int>& points)>;

// "two_level", "direct", "bicgstab", "gmres"; throws std::invalid_argument otherwise.
HarmonicSolver parse_harmonic_solver(const std::string& name);

// L         #P by #P meshless Laplacian (build_laplacian)
// boundary  a UVMap from map_boundary: outer_loop and boundary_uv are used, the rest copied
// Returns the map with uv (#P) filled and residual = ||A X - B||_F / ||B||_F of the interior
// system A X = B (X #interior by 2). Every point not on the outer loop is an unknown with its own
// Laplace row; points of inner loops (holes) are thereby free, natural boundaries: in the
// meshless setting their one-sided neighbourhood row is the natural-boundary discretisation.
// Outer-loop points keep boundary_uv exactly.
// fixed     Dirichlet values (point index, uv) of further points, or replacing boundary_uv of
//           outer-loop points (band_values gives both for the whole boundary band); these
//           points keep their uv exactly. The returned boundary_uv holds the values used.
// join      optional: where points cannot reach the fixed ones through their own rows (a region
//           whose nearest neighbours all lie inside it: the system is singular there), called
//           with them; the matrix it returns (L with their rows rebuilt, join_rows_both_ways in
//           laplacian.h) is solved instead. Without it, an error.
// Throws std::invalid_argument for mismatched sizes, and std::runtime_error when the solve fails
// (singular system: points not connected to the outer loop through neighbours either way) or its
// relative residual exceeds 1e-6.
UVMap solve_harmonic(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L, const UVMap& boundary,
                     HarmonicSolver solver = HarmonicSolver::TwoLevel,
                     const std::vector<std::pair<int, Eigen::Vector2d>>& fixed = {}, const JoinRows& join = {});

// The harmonic map with the whole outer boundary band fixed (boundary_map.h, BandPoint): a first
// solve with every band point on the domain's edge measures the map's derivative along the depth
// near the loop (band_depth_slope); the second fixes each band point at its depth inside the
// smoothed loop times that derivative (band_values), so the band keeps its geometry in (u,v) and neither the loop's
// zig-zag nor free band points fold the map at the edge.
// P, N, is_boundary, loops  as for outer_band; boundary  map_boundary of loops[0].
// progress  optional, called with the fraction done and what is being solved.
// join      as for solve_harmonic.
// Same errors as solve_harmonic and outer_band.
UVMap solve_harmonic_band(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                          const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                          const std::vector<std::uint8_t>& is_boundary,
                          const std::vector<std::vector<int>>& loops, const UVMap& boundary,
                          HarmonicSolver solver = HarmonicSolver::TwoLevel,
                          const std::function<void(double, const std::string&)>& progress = {},
                          const JoinRows& join = {});

}  // namespace scallop
