#include "nodes/param/two_level_solver.h"
#include "nodes/param/umfpack_lock.h"

#include <umfpack.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

namespace scallop {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

std::vector<int> breadth_first_order(const RowMatrix& A, const std::vector<int>& seeds) {
  const Eigen::Index n = A.rows();
  std::vector<int> order;
  order.reserve(n);
  std::vector<char> seen(n, 0);
  auto visit = [&](Eigen::Index i) {
    if (i < 0 || i >= n || seen[i]) return;
    seen[i] = 1;
    order.push_back(static_cast<int>(i));
  };
  for (int s : seeds) visit(s);
  for (Eigen::Index start = 0;; ++start) {
    for (std::size_t head = 0; head < order.size(); ++head)
      for (RowMatrix::InnerIterator it(A, order[head]); it; ++it) visit(it.col());
    while (start < n && seen[start]) ++start;
    if (start >= n) break;
    visit(start);
  }
  return order;
}

std::vector<int> aggregate_points(const RowMatrix& A) {
  const Eigen::Index n = A.rows();
  std::vector<int> agg(n, -1);
  int count = 0;
  // 1. A free point whose neighbours are all free seeds an aggregate of itself and them.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    bool free = true;
    for (RowMatrix::InnerIterator it(A, i); it && free; ++it) free = agg[it.col()] < 0;
    if (!free) continue;
    for (RowMatrix::InnerIterator it(A, i); it; ++it) agg[it.col()] = count;
    agg[i] = count++;
  }
  // 2. A point left over joins the first-pass aggregate it is most strongly connected to.
  const std::vector<int> seeded = agg;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    double best = 0;
    for (RowMatrix::InnerIterator it(A, i); it; ++it)
      if (it.col() != i && seeded[it.col()] >= 0 && std::abs(it.value()) > best) {
        best = std::abs(it.value());
        agg[i] = seeded[it.col()];
      }
  }
  // 3. Points with no aggregated neighbour (all of them joined in pass 2 elsewhere, or zero
  //    weights) make aggregates of their own with their free neighbours.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    for (RowMatrix::InnerIterator it(A, i); it; ++it)
      if (agg[it.col()] < 0) agg[it.col()] = count;
    agg[i] = count++;
  }
  return agg;
}

// The coarse matrix's LU factors, by UMFPACK's C interface: its solve takes the caller's own
// Info array, so the columns' GMRES runs can use the factors at once.
struct TwoLevelPreconditioner::Coarse {
  Eigen::SparseMatrix<double> Ac;  // column-compressed, as UMFPACK wants
  void* numeric = nullptr;
  double control[UMFPACK_CONTROL];
  ~Coarse() {
    if (numeric) umfpack_di_free_numeric(&numeric);
  }
};

TwoLevelPreconditioner::TwoLevelPreconditioner() = default;
TwoLevelPreconditioner::~TwoLevelPreconditioner() = default;
TwoLevelPreconditioner::TwoLevelPreconditioner(TwoLevelPreconditioner&&) noexcept = default;
TwoLevelPreconditioner& TwoLevelPreconditioner::operator=(TwoLevelPreconditioner&&) noexcept = default;

Eigen::Index TwoLevelPreconditioner::coarse_size() const { return coarse_ ? coarse_->Ac.rows() : 0; }

bool TwoLevelPreconditioner::build(const RowMatrix& A, int sweeps) {
  if (sweeps < 1) throw std::invalid_argument("sweeps must be at least 1");
  if (A.rows() != A.cols()) throw std::invalid_argument("the matrix is not square");
  ok_ = false;
  A_ = &A;
  sweeps_ = sweeps;
  const Eigen::Index n = A.rows();
  const RowMatrix* C = &A;
  if (!A.isCompressed()) {
    compressed_ = A;
    compressed_.makeCompressed();
    C = &compressed_;
  }
  row_start_ = C->outerIndexPtr();
  column_ = C->innerIndexPtr();
  value_.resize(C->nonZeros());
  inv_diag_.assign(n, 0.0);
  std::atomic<bool> singular = false;
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 4096), [&](const tbb::blocked_range<Eigen::Index>& rows) {
    for (Eigen::Index i = rows.begin(); i < rows.end(); ++i) {
      for (int e = row_start_[i]; e < row_start_[i + 1]; ++e) {
        value_[e] = static_cast<float>(C->valuePtr()[e]);
        if (column_[e] == i) inv_diag_[i] = value_[e];
      }
      if (!(inv_diag_[i] != 0) || !std::isfinite(inv_diag_[i])) singular = true;
      inv_diag_[i] = 1 / inv_diag_[i];
    }
  });
  if (singular) return false;
  aggregate_ = aggregate_points(A);
  const int nc = n == 0 ? 0 : *std::max_element(aggregate_.begin(), aggregate_.end()) + 1;
  // Ac = P^T A P: the sum of A's entries between the points of two aggregates.
  std::vector<std::vector<int>> members(nc);
  for (Eigen::Index i = 0; i < n; ++i) members[aggregate_[i]].push_back(static_cast<int>(i));
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> sum(nc, 0.0);
  std::vector<int> row_of(nc, -1);  // the coarse row whose sum[d] is being gathered
  std::vector<int> touched;
  for (int c = 0; c < nc; ++c) {
    for (int i : members[c])
      for (RowMatrix::InnerIterator it(A, i); it; ++it) {
        const int d = aggregate_[it.col()];
        if (row_of[d] != c) row_of[d] = c, sum[d] = 0, touched.push_back(d);
        sum[d] += it.value();
      }
    for (int d : touched) trip.emplace_back(c, d, sum[d]);
    touched.clear();
  }
  auto coarse = std::make_unique<Coarse>();
  coarse->Ac.resize(nc, nc);
  coarse->Ac.setFromTriplets(trip.begin(), trip.end());
  coarse->Ac.makeCompressed();
  umfpack_di_defaults(coarse->control);
  coarse->control[UMFPACK_IRSTEP] = 0;  // a preconditioner needs the factors, not refinement
  const int* Ap = coarse->Ac.outerIndexPtr();
  const int* Ai = coarse->Ac.innerIndexPtr();
  const double* Ax = coarse->Ac.valuePtr();
  void* symbolic = nullptr;
  double info[UMFPACK_INFO];
  std::lock_guard lock(umfpack_mutex());
  if (umfpack_di_symbolic(nc, nc, Ap, Ai, Ax, &symbolic, coarse->control, info) != UMFPACK_OK) {
    if (symbolic) umfpack_di_free_symbolic(&symbolic);
    return false;
  }
  const int status = umfpack_di_numeric(Ap, Ai, Ax, symbolic, &coarse->numeric, coarse->control, info);
  umfpack_di_free_symbolic(&symbolic);
  if (status != UMFPACK_OK) return false;  // includes a singular coarse matrix (a warning code)
  coarse_ = std::move(coarse);
  ok_ = true;
  return true;
}

Eigen::VectorXd TwoLevelPreconditioner::apply(const Eigen::VectorXd& r) const {
  if (!ok_) throw std::logic_error("TwoLevelPreconditioner::apply before a successful build");
  const Eigen::Index n = A_->rows();
  const int* start = row_start_;
  const int* column = column_;
  const float* value = value_.data();
  // The row's residual r_i - sum_j a_ij z_j, the diagonal included (no branch in the loop).
  auto residual = [&](const Eigen::VectorXd& z, Eigen::Index i) {
    double s = r[i];
    for (int e = start[i]; e < start[i + 1]; ++e) s -= double(value[e]) * z[column[e]];
    return s;
  };
  // Coarse correction first, on r's aggregate sums (z starts at zero, so the residual is r
  // itself and needs no pass over the matrix), then the sweeps.
  const Eigen::Index nc = coarse_->Ac.rows();
  Eigen::VectorXd rc = Eigen::VectorXd::Zero(nc), zc(nc);
  for (Eigen::Index i = 0; i < n; ++i) rc[aggregate_[i]] += r[i];
  double info[UMFPACK_INFO];
  {
    std::lock_guard lock(umfpack_mutex());
    umfpack_di_solve(UMFPACK_A, coarse_->Ac.outerIndexPtr(), coarse_->Ac.innerIndexPtr(), coarse_->Ac.valuePtr(),
                     zc.data(), rc.data(), coarse_->numeric, coarse_->control, info);
  }
  Eigen::VectorXd z(n);
  for (Eigen::Index i = 0; i < n; ++i) z[i] = zc[aggregate_[i]];
  for (int s = 0; s < sweeps_; ++s)
    for (Eigen::Index i = 0; i < n; ++i) z[i] += residual(z, i) * inv_diag_[i];
  for (int s = 0; s < sweeps_; ++s)
    for (Eigen::Index i = n - 1; i >= 0; --i) z[i] += residual(z, i) * inv_diag_[i];
  return z;
}

namespace {

// Restarted GMRES with the preconditioner on the right: the Krylov space of A M^-1, x = x0 +
// M^-1 V y, so the residual it minimises is b - A x itself (Saad, algorithm 9.5).
bool gmres_right(const RowMatrix& A, const TwoLevelPreconditioner& M, const Eigen::VectorXd& b,
                 Eigen::VectorXd& x, double tolerance, int max_iterations, int& iterations) {
  constexpr int kRestart = 30;
  const double bnorm = b.norm();
  const double target = tolerance * (bnorm > 0 ? bnorm : 1.0);
  Eigen::VectorXd r = b - A * x;
  double beta = r.norm();
  iterations = 0;
  Eigen::MatrixXd V(A.rows(), kRestart + 1);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(kRestart + 1, kRestart);
  Eigen::VectorXd cs(kRestart), sn(kRestart), g(kRestart + 1);
  while (beta > target && iterations < max_iterations) {
    V.col(0) = r / beta;
    g.setZero();
    g[0] = beta;
    int j = 0;
    for (; j < kRestart && iterations < max_iterations; ++j, ++iterations) {
      Eigen::VectorXd w = A * M.apply(V.col(j));
      for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
        H(i, j) = w.dot(V.col(i));
        w -= H(i, j) * V.col(i);
      }
      H(j + 1, j) = w.norm();
      if (H(j + 1, j) > 0) V.col(j + 1) = w / H(j + 1, j);
      for (int i = 0; i < j; ++i) {  // the earlier rotations, then this column's own
        const double t = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
        H(i + 1, j) = -sn[i] * H(i, j) + cs[i] * H(i + 1, j);
        H(i, j) = t;
      }
      const double d = std::hypot(H(j, j), H(j + 1, j));
      cs[j] = d > 0 ? H(j, j) / d : 1.0;
      sn[j] = d > 0 ? H(j + 1, j) / d : 0.0;
      H(j, j) = d;
      H(j + 1, j) = 0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      if (std::abs(g[j + 1]) <= target || !(H(j, j) > 0)) {
        ++j, ++iterations;
        break;
      }
    }
    if (j == 0) break;
    const Eigen::VectorXd y =
        H.topLeftCorner(j, j).triangularView<Eigen::Upper>().solve(g.head(j));
    x += M.apply(V.leftCols(j) * y);
    r = b - A * x;
    const double previous = beta;
    beta = r.norm();
    if (!(beta < previous)) break;  // stagnation (or NaN): give up, the caller falls back
  }
  return beta <= target;
}

}  // namespace

TwoLevelResult solve_two_level(const RowMatrix& A, const TwoLevelPreconditioner& M, const Eigen::MatrixXd& B,
                               const Eigen::MatrixXd& X0, double tolerance, int max_iterations) {
  TwoLevelResult out;
  out.X = X0.size() ? X0 : Eigen::MatrixXd::Zero(A.rows(), B.cols());
  if (out.X.rows() != A.rows() || out.X.cols() != B.cols() || B.rows() != A.rows())
    throw std::invalid_argument("solve_two_level: the start or the right-hand side does not match the matrix");
  std::vector<int> its(B.cols(), 0);
  std::vector<char> done(B.cols(), 0);
  tbb::parallel_for(Eigen::Index(0), B.cols(), [&](Eigen::Index c) {
    Eigen::VectorXd x = out.X.col(c);
    done[c] = gmres_right(A, M, B.col(c), x, tolerance, max_iterations, its[c]);
    out.X.col(c) = x;
  });
  out.converged = std::all_of(done.begin(), done.end(), [](char d) { return d != 0; });
  for (int i : its) out.iterations += i;
  return out;
}

}  // namespace scallop
