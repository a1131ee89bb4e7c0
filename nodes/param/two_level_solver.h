// A two-level preconditioned Krylov solve for the harmonic map's sparse systems: a meshless
// Laplacian's interior rows (rows summing to zero or nearly so, one row per point, a few tens of
// entries per row, not symmetric).
//
// Preconditioner (one application z = M^-1 r, a fixed linear operator):
//   1. coarse correction z = P Ac^-1 P^T r, Ac = P^T A P, where P is piecewise constant on
//      aggregates: each aggregate a point and its still free neighbours (greedy, in index order),
//      leftovers joined to the aggregate they are most strongly connected to. Constants are what
//      a Laplacian's rows annihilate, so P carries the smooth error that Gauss-Seidel leaves; Ac,
//      about #A / 20 unknowns, is factorised once by UMFPACK (sparse LU);
//   2. forward, then backward Gauss-Seidel sweeps on A z = r from there (the smoother: it damps
//      the error that varies from point to point).
//   Taking the coarse correction first spares the pass over the matrix that a residual after a
//   first sweep costs, and GMRES needed fewer iterations with it (bench/harmonic_solvers at a
//   million points: 40 + 37 against 44 + 39).
// With an exact coarse solve this two-level method's convergence does not degrade with the number
// of points (the aggregates keep a bounded size in neighbour hops): Vanek, Mandel, Brezina,
// "Algebraic multigrid by smoothed aggregation", Computing 56 (1996), for the aggregates;
// Notay, "An aggregation-based algebraic multigrid method", ETNA 37 (2010), for unsmoothed
// aggregation inside a Krylov method. The accelerator is restarted GMRES with the preconditioner
// on the right (Saad, "Iterative methods for sparse linear systems", 2nd ed., algorithm 9.5), so
// the residual it watches is the system's own.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace scallop {

// The points of A's graph (row i's off-diagonal columns are i's neighbours) breadth first from
// `seeds` (Cuthill-McKee's order without its degree sort), then any not reached, in index order.
// Neighbours end up near one another in the order, so sweeps over the rows of a matrix numbered so
// read memory nearly in sequence (a scanned cloud comes in any order: a random one made Gauss-
// Seidel and the products 4 times slower at a million points).
// Returns #n distinct indices.
std::vector<int> breadth_first_order(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A,
                                     const std::vector<int>& seeds);

// Aggregates of the graph of A's off-diagonal nonzeros (both directions).
// A      #n by #n sparse matrix, nonzero diagonal
// Returns #n aggregate indices in [0, #aggregates); every aggregate holds at least one point,
// and every point of an aggregate is A-connected to its seed or to a point joined to it.
std::vector<int> aggregate_points(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A);

class TwoLevelPreconditioner {
 public:
  TwoLevelPreconditioner();
  ~TwoLevelPreconditioner();
  TwoLevelPreconditioner(TwoLevelPreconditioner&&) noexcept;
  TwoLevelPreconditioner& operator=(TwoLevelPreconditioner&&) noexcept;

  // A  #n by #n, the system's matrix (kept by reference: it must outlive this object).
  // sweeps  Gauss-Seidel sweeps before and after the coarse correction, >= 1.
  // False when a diagonal entry is zero or the coarse matrix is singular.
  bool build(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, int sweeps = 1);
  // z = M^-1 r, #n.
  Eigen::VectorXd apply(const Eigen::VectorXd& r) const;
  Eigen::Index coarse_size() const;

 private:
  struct Coarse;
  const Eigen::SparseMatrix<double, Eigen::RowMajor>* A_ = nullptr;
  Eigen::SparseMatrix<double, Eigen::RowMajor> compressed_;  // A's copy when A was not compressed
  const int* row_start_ = nullptr;  // #n + 1, A's compressed rows ...
  const int* column_ = nullptr;     // #nonzeros
  // ... and its values in single precision for the sweeps: they stream the whole matrix three
  // times per application, bound by memory bandwidth, and 8 bytes per entry instead of 12 make
  // them faster (measured at a million points); the operator stays a fixed linear one, and GMRES
  // measures the residual with A itself.
  std::vector<float> value_;
  std::vector<double> inv_diag_;  // 1 / the single-precision diagonal
  std::vector<int> aggregate_;
  std::unique_ptr<Coarse> coarse_;
  int sweeps_ = 1;
  bool ok_ = false;
};

struct TwoLevelResult {
  Eigen::MatrixXd X;  // #n by #B.cols()
  int iterations = 0; // GMRES iterations, summed over the columns
  bool converged = false;
};

// Solves A X = B column by column (the columns in parallel) with restarted, right-preconditioned
// GMRES, M built on A, from the start X0 (#n by #B.cols(), or empty: zero), until
// ||A x - b|| <= tolerance ||b|| for every column or `max_iterations` per column (then
// converged = false and X is the last iterate).
TwoLevelResult solve_two_level(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A,
                               const TwoLevelPreconditioner& M, const Eigen::MatrixXd& B,
                               const Eigen::MatrixXd& X0, double tolerance, int max_iterations = 500);

}  // namespace scallop
