#include "nodes/param/laplacian.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "nodes/geom/tangent_frame.h"

namespace scallop {

LaplacianScheme parse_laplacian_scheme(const std::string& name) {
  if (name == "uniform") return LaplacianScheme::Uniform;
  if (name == "heat") return LaplacianScheme::Heat;
  if (name == "optimal") return LaplacianScheme::Optimal;
  throw std::invalid_argument("unknown Laplacian scheme '" + name + "' (uniform, heat, optimal)");
}

std::string to_string(LaplacianScheme scheme) {
  switch (scheme) {
    case LaplacianScheme::Uniform: return "uniform";
    case LaplacianScheme::Heat: return "heat";
    case LaplacianScheme::Optimal: return "optimal";
  }
  return "?";
}

double mean_sq_neighbor_distance(const Neighborhoods& nbrs) {
  double s = 0;
  for (double d : nbrs.sq_dists) s += d;
  return nbrs.sq_dists.empty() ? 0.0 : s / static_cast<double>(nbrs.sq_dists.size());
}

namespace {

// Normal of the least-variance direction of p_i and its neighbours (for clouds without normals).
Eigen::Vector3d local_pca_normal(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nb,
                                 std::size_t i) {
  Eigen::Vector3d c = P[i];
  for (int j = 0; j < nb.k; ++j) c += P[nb.index(i, j)];
  c /= nb.k + 1;
  Eigen::Matrix3d cov = (P[i] - c) * (P[i] - c).transpose();
  for (int j = 0; j < nb.k; ++j) cov += (P[nb.index(i, j)] - c) * (P[nb.index(i, j)] - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  return es.eigenvectors().col(0);
}

// Scratch matrices of optimal_weights, kept across the points of one thread's range (a heap
// allocation per point and matrix cost more than the arithmetic).
struct WeightScratch {
  Eigen::MatrixXd D, C, A;
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
};

// Optimal weights of one point (see header). w has k entries and sums to 1.
void optimal_weights(const std::vector<Eigen::Vector3d>& P, const Eigen::Vector3d& n,
                     const Neighborhoods& nb, std::size_t i, double delta, Eigen::VectorXd& w,
                     WeightScratch& s) {
  const int k = nb.k;
  Eigen::Vector3d t1, t2;
  tangent_frame(n, t1, t2);
  Eigen::MatrixXd& D = s.D;  // tangent-plane components of p_i - p_j' (= of p_i - p_j)
  D.resize(2, k);
  for (int j = 0; j < k; ++j) {
    Eigen::Vector3d d = P[i] - P[nb.index(i, j)];
    D(0, j) = d.dot(t1);
    D(1, j) = d.dot(t2);
  }
  Eigen::MatrixXd& C = s.C;
  C.noalias() = D.transpose() * D;
  double tr = C.trace();
  if (!(tr > 0)) {  // every neighbour coincides with p_i in the tangent plane: no geometry
    w.setConstant(k, 1.0 / k);
    return;
  }
  C.diagonal().array() += delta * tr;
  s.ldlt.compute(C);
  w = s.ldlt.solve(Eigen::VectorXd::Ones(k));
  w /= w.sum();
  // Least-change projection onto {D w = 0, 1^T w = 1}, in units of the rms distance so that the
  // three constraint rows are commensurate.
  Eigen::MatrixXd& A = s.A;
  A.resize(3, k);
  A.topRows(2) = D / std::sqrt(tr / k);
  A.row(2).setOnes();
  Eigen::Matrix3d AAt = A * A.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(AAt);
  if (es.eigenvalues()(0) <= 1e-10 * es.eigenvalues()(2)) return;  // collinear neighbours
  Eigen::Vector3d r = A * w - Eigen::Vector3d(0, 0, 1);
  w -= A.transpose() * AAt.ldlt().solve(r);
}

}  // namespace

Eigen::SparseMatrix<double, Eigen::RowMajor> build_laplacian(const std::vector<Eigen::Vector3d>& P,
                                                             const std::vector<Eigen::Vector3d>& N,
                                                             const Neighborhoods& nbrs,
                                                             LaplacianScheme scheme, double t,
                                                             double regularization,
                                                             const std::function<void(double)>& progress) {
  const std::size_t n = P.size();
  const int k = nbrs.k;
  if (n == 0) throw std::invalid_argument("the cloud is empty");
  if (nbrs.size() != n || nbrs.sq_dists.size() != nbrs.indices.size())
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(nbrs.size()) +
                                " points but the cloud has " + std::to_string(n));
  if (k < 1) throw std::invalid_argument("the Laplacian needs at least 1 neighbour per point");
  if (scheme == LaplacianScheme::Optimal && k < 3)
    throw std::invalid_argument("the optimal Laplacian needs k >= 3 neighbours per point (k = " +
                                std::to_string(k) + ")");
  if (!N.empty() && N.size() != n)
    throw std::invalid_argument("the cloud has " + std::to_string(N.size()) + " normals for " +
                                std::to_string(n) + " points");
  if (!(regularization > 0) || !std::isfinite(regularization))
    throw std::invalid_argument("the regularization must be positive");
  for (std::size_t i = 0; i < n; ++i)
    if (!P[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) + " has a non-finite coordinate");
  for (int idx : nbrs.indices)
    if (idx < 0 || static_cast<std::size_t>(idx) >= n)
      throw std::invalid_argument("a neighbour index is out of range");

  if (scheme == LaplacianScheme::Heat && !(t > 0)) t = mean_sq_neighbor_distance(nbrs);
  if (scheme == LaplacianScheme::Heat && !(t > 0)) t = 1.0;  // all points coincide: any t works

  std::vector<double> W(n * static_cast<std::size_t>(k));
  ParallelProgress done(progress, n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    Eigen::VectorXd w(k);
    WeightScratch scratch;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      switch (scheme) {
        case LaplacianScheme::Uniform: w.setConstant(1.0); break;
        case LaplacianScheme::Heat:
          for (int j = 0; j < k; ++j) w(j) = std::exp(-nbrs.sq_dist(i, j) / t);
          break;
        case LaplacianScheme::Optimal: {
          Eigen::Vector3d nrm = N.empty() ? local_pca_normal(P, nbrs, i) : N[i];
          optimal_weights(P, nrm, nbrs, i, regularization, w, scratch);
          break;
        }
      }
      double s = w.sum();
      if (!(std::abs(s) > 0)) {  // heat kernel underflow: every neighbour is far beyond sqrt(t)
        w.setConstant(1.0);
        s = k;
      }
      for (int j = 0; j < k; ++j) W[i * k + j] = w(j) / s;
    }
    done.done(r.size());
  });

  // Row i: -w_ij at its neighbours' columns and the weights' sum on the diagonal (1 up to
  // rounding; so that the row sums to zero to the last bit), columns sorted, written straight
  // into the compressed arrays: row i's entries are its distinct neighbours other than i, plus i.
  auto row_entries = [&](std::size_t i, std::vector<std::pair<int, double>>& e) {
    e.clear();
    double s = 0;
    for (int j = 0; j < k; ++j) {
      const int c = nbrs.index(i, j);
      if (static_cast<std::size_t>(c) == i) continue;  // a self index would cancel out anyway
      e.emplace_back(c, -W[i * k + j]);
      s += W[i * k + j];
    }
    e.emplace_back(static_cast<int>(i), 0.0);
    std::sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::size_t m = 0;  // merge repeated neighbours
    for (std::size_t q = 0; q < e.size(); ++q) {
      if (m > 0 && e[m - 1].first == e[q].first)
        e[m - 1].second += e[q].second;
      else
        e[m++] = e[q];
    }
    e.resize(m);
    for (auto& [c, v] : e)
      if (static_cast<std::size_t>(c) == i) v += s;
  };
  // Each row's entries are made twice, to count them and then to write them, rather than kept
  // between the passes: that would be a second #P (k + 1) array (200 MB at a million points).
  Eigen::SparseMatrix<double, Eigen::RowMajor> L(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  std::vector<int> count(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::pair<int, double>> e;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      row_entries(i, e);
      count[i] = static_cast<int>(e.size());
    }
  });
  std::size_t nnz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    L.outerIndexPtr()[i] = static_cast<int>(nnz);
    nnz += count[i];
  }
  L.outerIndexPtr()[n] = static_cast<int>(nnz);
  L.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::pair<int, double>> e;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      row_entries(i, e);
      std::size_t at = L.outerIndexPtr()[i];
      for (const auto& [c, v] : e) {
        L.innerIndexPtr()[at] = c;
        L.valuePtr()[at++] = v;
      }
    }
  });
  L.makeCompressed();
  return L;
}

}  // namespace scallop
