#include "nodes/param/two_level_solver.h"

#include <gtest/gtest.h>

#include <Eigen/SparseLU>
#include <algorithm>
#include <random>
#include <set>
#include <vector>

namespace scallop {
namespace {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// The interior rows of the 5-point Laplacian on an (n+2) x (n+2) grid of spacing 1, Dirichlet
// values g(x, y) on its border moved to the right-hand side: unknown (x, y), 1 <= x, y <= n, has
// index (y - 1) n + (x - 1). Row i: u_i - (u_E + u_W + u_N + u_S) / 4 (random-walk form, as the
// meshless Laplacian's rows).
template <class G>
void grid_laplacian(int n, G g, RowMatrix& A, Eigen::VectorXd& b) {
  std::vector<Eigen::Triplet<double>> t;
  b = Eigen::VectorXd::Zero(n * n);
  auto id = [n](int x, int y) { return (y - 1) * n + (x - 1); };
  for (int y = 1; y <= n; ++y)
    for (int x = 1; x <= n; ++x) {
      const int i = id(x, y);
      t.emplace_back(i, i, 1.0);
      const int nx[4] = {x + 1, x - 1, x, x};
      const int ny[4] = {y, y, y + 1, y - 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 1 || nx[k] > n || ny[k] < 1 || ny[k] > n)
          b[i] += 0.25 * g(nx[k], ny[k]);
        else
          t.emplace_back(i, id(nx[k], ny[k]), -0.25);
      }
    }
  A.resize(n * n, n * n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
}

TEST(TwoLevelSolver, AggregatesCoverEveryPointAndAreConnected) {
  RowMatrix A;
  Eigen::VectorXd b;
  const int n = 40;
  grid_laplacian(n, [](int, int) { return 0.0; }, A, b);
  const std::vector<int> agg = aggregate_points(A);
  ASSERT_EQ(agg.size(), static_cast<std::size_t>(n * n));
  const int count = *std::max_element(agg.begin(), agg.end()) + 1;
  std::vector<std::vector<int>> members(count);
  for (int i = 0; i < n * n; ++i) {
    ASSERT_GE(agg[i], 0);
    members[agg[i]].push_back(i);
  }
  for (int c = 0; c < count; ++c) {
    ASSERT_FALSE(members[c].empty()) << "aggregate " << c;
    // connected through A's nonzeros inside the aggregate
    std::set<int> reached{members[c][0]};
    std::vector<int> stack{members[c][0]};
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      for (RowMatrix::InnerIterator it(A, i); it; ++it)
        if (agg[it.col()] == c && reached.insert(static_cast<int>(it.col())).second) stack.push_back(it.col());
    }
    EXPECT_EQ(reached.size(), members[c].size()) << "aggregate " << c;
  }
  // a 5-point stencil seeds aggregates of 5; leftovers join them: between 1/9 and 1/3 of the points
  EXPECT_GE(count, n * n / 9);
  EXPECT_LE(count, n * n / 3);
}

TEST(TwoLevelSolver, SolvesAGridLaplacianExactly) {
  // x^2 - y^2 is exactly harmonic for the 5-point stencil: the solve must give it back.
  const int n = 150;
  auto g = [](int x, int y) { return double(x) * x - double(y) * y; };
  RowMatrix A;
  Eigen::VectorXd b;
  grid_laplacian(n, g, A, b);
  TwoLevelPreconditioner M;
  ASSERT_TRUE(M.build(A));
  EXPECT_GT(M.coarse_size(), n * n / 9);
  EXPECT_LT(M.coarse_size(), n * n / 3);
  const TwoLevelResult r = solve_two_level(A, M, b, Eigen::MatrixXd(), 1e-12);
  ASSERT_TRUE(r.converged);
  EXPECT_LE((A * r.X.col(0) - b).norm(), 1e-12 * b.norm());
  double err = 0;
  for (int y = 1; y <= n; ++y)
    for (int x = 1; x <= n; ++x) err = std::max(err, std::abs(r.X((y - 1) * n + (x - 1), 0) - g(x, y)));
  // values up to 22 500; the residual's 1e-12 bounds the error through the grid Laplacian's
  // conditioning (about n^2), so to 1e-11 of the largest value
  EXPECT_LT(err, 1e-11 * n * n);
  // the number of iterations does not grow with the grid: a two-level method
  EXPECT_LT(r.iterations, 40);
}

TEST(TwoLevelSolver, AMatrixNotCompressedGivesTheSameOperator) {
  // The sweeps read the compressed rows; a matrix with room left in its rows (inserted entry by
  // entry) must give the same preconditioner as its compressed copy, bit for bit.
  const int n = 40;
  RowMatrix compressed;
  Eigen::VectorXd b;
  grid_laplacian(n, [](int x, int y) { return double(x) * y; }, compressed, b);
  RowMatrix loose(compressed.rows(), compressed.cols());
  loose.reserve(Eigen::VectorXi::Constant(compressed.rows(), 8));
  for (Eigen::Index i = 0; i < compressed.rows(); ++i)
    for (RowMatrix::InnerIterator it(compressed, i); it; ++it) loose.insert(i, it.col()) = it.value();
  ASSERT_FALSE(loose.isCompressed());
  TwoLevelPreconditioner from_compressed, from_loose;
  ASSERT_TRUE(from_compressed.build(compressed));
  ASSERT_TRUE(from_loose.build(loose));
  const Eigen::VectorXd z1 = from_compressed.apply(b), z2 = from_loose.apply(b);
  EXPECT_EQ(z1, z2);
  EXPECT_GT(z1.norm(), 0);
}

TEST(TwoLevelSolver, AgreesWithSparseLUOnANonSymmetricSystem) {
  // Random-walk rows with unequal, partly negative weights (as the optimal weights have), two
  // right-hand sides solved at once.
  const int n = 60;
  RowMatrix A0;
  Eigen::VectorXd b0;
  grid_laplacian(n, [](int, int) { return 1.0; }, A0, b0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> w(-0.2, 1.0);
  std::vector<Eigen::Triplet<double>> t;
  Eigen::MatrixXd B(n * n, 2);
  for (int i = 0; i < n * n; ++i) {
    std::vector<std::pair<int, double>> row;
    double sum = 0;
    for (RowMatrix::InnerIterator it(A0, i); it; ++it)
      if (it.col() != i) row.emplace_back(it.col(), w(rng) + 0.3), sum += row.back().second;
    const double boundary = 4 - static_cast<double>(row.size());  // missing neighbours
    const double total = sum + boundary * 0.7;
    t.emplace_back(i, i, 1.0);
    for (auto [j, v] : row) t.emplace_back(i, j, -v / total);
    B(i, 0) = boundary * 0.7 / total;
    B(i, 1) = boundary * 0.7 / total * (i % n) / n;
  }
  RowMatrix A(n * n, n * n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  TwoLevelPreconditioner M;
  ASSERT_TRUE(M.build(A, 2));
  const TwoLevelResult r = solve_two_level(A, M, B, Eigen::MatrixXd(), 1e-12);
  ASSERT_TRUE(r.converged);
  Eigen::SparseMatrix<double> Ac = A;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(Ac);
  ASSERT_EQ(lu.info(), Eigen::Success);
  const Eigen::MatrixXd X = lu.solve(B);
  EXPECT_LT((r.X - X).cwiseAbs().maxCoeff(), 1e-9);
  // the first column is the constant 1: rows sum to zero with the boundary's share
  EXPECT_LT((r.X.col(0).array() - 1).abs().maxCoeff(), 1e-9);
}

TEST(TwoLevelSolver, AStartThatIsTheAnswerTakesNoIteration) {
  const int n = 30;
  auto g = [](int x, int y) { return double(x + 2 * y); };
  RowMatrix A;
  Eigen::VectorXd b;
  grid_laplacian(n, g, A, b);
  TwoLevelPreconditioner M;
  ASSERT_TRUE(M.build(A));
  Eigen::MatrixXd X0(n * n, 1);
  for (int y = 1; y <= n; ++y)
    for (int x = 1; x <= n; ++x) X0((y - 1) * n + (x - 1), 0) = g(x, y);
  const TwoLevelResult r = solve_two_level(A, M, b, X0, 1e-10);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);
}

TEST(TwoLevelSolver, BadInput) {
  RowMatrix zero_diagonal(2, 2);
  zero_diagonal.insert(0, 1) = 1;
  zero_diagonal.insert(1, 0) = 1;
  TwoLevelPreconditioner M;
  EXPECT_FALSE(M.build(zero_diagonal));
  EXPECT_THROW(M.apply(Eigen::VectorXd::Ones(2)), std::logic_error);
  RowMatrix rect(2, 3);
  EXPECT_THROW(M.build(rect), std::invalid_argument);
  RowMatrix A;
  Eigen::VectorXd b;
  grid_laplacian(4, [](int, int) { return 1.0; }, A, b);
  EXPECT_THROW(M.build(A, 0), std::invalid_argument);
  ASSERT_TRUE(M.build(A));
  EXPECT_THROW(solve_two_level(A, M, Eigen::MatrixXd::Ones(3, 1), Eigen::MatrixXd(), 1e-10), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
