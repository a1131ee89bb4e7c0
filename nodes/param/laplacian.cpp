#include "nodes/param/laplacian.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
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

double heat_time(const Neighborhoods& nbrs, double t) {
  if (!(t > 0)) t = mean_sq_neighbor_distance(nbrs);
  return t > 0 ? t : 1.0;  // all points coincide: any t works
}

namespace {

// Normal of the least-variance direction of p_i and its k neighbours idx (for clouds without
// normals).
Eigen::Vector3d local_pca_normal(const std::vector<Eigen::Vector3d>& P, std::size_t i, const int* idx, int k) {
  Eigen::Vector3d c = P[i];
  for (int j = 0; j < k; ++j) c += P[idx[j]];
  c /= k + 1;
  Eigen::Matrix3d cov = (P[i] - c) * (P[i] - c).transpose();
  for (int j = 0; j < k; ++j) cov += (P[idx[j]] - c) * (P[idx[j]] - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  return es.eigenvectors().col(0);
}

// Optimal weights of one point (see header). w has k entries and sums to 1.
// C = D^T D has rank 2 (D: the k offsets' tangent-plane components, 2 x k), so the k x k system
// (C + eps I) w = 1 is solved through its 2 x 2 form (Sherman-Morrison-Woodbury):
// (eps I + D^T D)^-1 1 = (1 - D^T (eps I + D D^T)^-1 D 1) / eps; the 1 / eps goes with the
// normalisation to sum 1. The same weights as a k x k factorisation, in O(k) instead of O(k^3).
void optimal_weights(const std::vector<Eigen::Vector3d>& P, const Eigen::Vector3d& n, std::size_t i, const int* idx,
                     int k, double delta, Eigen::VectorXd& w, Eigen::Matrix2Xd& D) {
  Eigen::Vector3d t1, t2;
  tangent_frame(n, t1, t2);
  D.resize(2, k);  // tangent-plane components of p_i - p_j' (= of p_i - p_j)
  for (int j = 0; j < k; ++j) {
    Eigen::Vector3d d = P[i] - P[idx[j]];
    D(0, j) = d.dot(t1);
    D(1, j) = d.dot(t2);
  }
  const Eigen::Matrix2d DDt = D * D.transpose();
  const double tr = DDt.trace();  // = trace(D^T D)
  if (!(tr > 0)) {  // every neighbour coincides with p_i in the tangent plane: no geometry
    w.setConstant(k, 1.0 / k);
    return;
  }
  const Eigen::Vector2d s = D.rowwise().sum();
  const Eigen::Vector2d y = (DDt + delta * tr * Eigen::Matrix2d::Identity()).llt().solve(s);
  w = (1.0 - (D.transpose() * y).array()).matrix();
  w /= w.sum();
  // Least-change projection onto {D w = 0, 1^T w = 1}, in units of the rms distance so that the
  // three constraint rows are commensurate: A = [D / rho; 1^T], rho^2 = trace / k.
  const double rho = std::sqrt(tr / k);
  Eigen::Matrix3d AAt;
  AAt.topLeftCorner<2, 2>() = DDt / (rho * rho);
  AAt.topRightCorner<2, 1>() = s / rho;
  AAt.bottomLeftCorner<1, 2>() = s.transpose() / rho;
  AAt(2, 2) = k;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(AAt, Eigen::EigenvaluesOnly);
  if (es.eigenvalues()(0) <= 1e-10 * es.eigenvalues()(2)) return;  // collinear neighbours
  Eigen::Vector3d r;
  r.head<2>() = D * w / rho;
  r(2) = w.sum() - 1;
  const Eigen::Vector3d z = AAt.ldlt().solve(r);
  w -= D.transpose() * z.head<2>() / rho;
  w.array() -= z(2);
}

// The weights of row i over its k neighbours idx (sq their squared distances), not yet
// normalised: w has k entries.
void row_weights(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N, std::size_t i,
                 const int* idx, const double* sq, int k, LaplacianScheme scheme, double t, double regularization,
                 Eigen::VectorXd& w, Eigen::Matrix2Xd& D) {
  w.resize(k);
  switch (scheme) {
    case LaplacianScheme::Uniform: w.setConstant(1.0); break;
    case LaplacianScheme::Heat:
      for (int j = 0; j < k; ++j) w(j) = std::exp(-sq[j] / t);
      break;
    case LaplacianScheme::Optimal: {
      const Eigen::Vector3d nrm = N.empty() ? local_pca_normal(P, i, idx, k) : N[i];
      optimal_weights(P, nrm, i, idx, k, regularization, w, D);
      break;
    }
  }
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

  if (scheme == LaplacianScheme::Heat) t = heat_time(nbrs, t);

  // Row i: -w_ij at its neighbours' columns and the weights' sum on the diagonal (1 up to
  // rounding; so that the row sums to zero to the last bit), columns sorted, written straight
  // into the compressed arrays: row i's entries are its distinct neighbours other than i, plus i.
  // A first pass counts them (from the indices alone), the second computes each row's weights and
  // writes them where the counts put the row: no #P k array of weights between the two.
  Eigen::SparseMatrix<double, Eigen::RowMajor> L(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  std::vector<int> count(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<int> cols;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      cols.assign(nbrs.indices.begin() + i * k, nbrs.indices.begin() + (i + 1) * k);
      cols.push_back(static_cast<int>(i));
      std::sort(cols.begin(), cols.end());
      count[i] = static_cast<int>(std::unique(cols.begin(), cols.end()) - cols.begin());
    }
  });
  std::size_t nnz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    L.outerIndexPtr()[i] = static_cast<int>(nnz);
    nnz += count[i];
  }
  L.outerIndexPtr()[n] = static_cast<int>(nnz);
  L.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  ParallelProgress done(progress, n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    Eigen::VectorXd w(k);
    Eigen::Matrix2Xd D;
    std::vector<std::pair<int, double>> e;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      row_weights(P, N, i, &nbrs.indices[i * k], &nbrs.sq_dists[i * k], k, scheme, t, regularization, w, D);
      double sum = w.sum();
      if (!(std::abs(sum) > 0)) {  // heat kernel underflow: every neighbour is far beyond sqrt(t)
        w.setConstant(1.0);
        sum = k;
      }
      e.clear();
      double s = 0;
      for (int j = 0; j < k; ++j) {
        const int c = nbrs.index(i, j);
        if (static_cast<std::size_t>(c) == i) continue;  // a self index would cancel out anyway
        const double wij = w(j) / sum;
        e.emplace_back(c, -wij);
        s += wij;
      }
      e.emplace_back(static_cast<int>(i), 0.0);
      std::sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      std::size_t at = L.outerIndexPtr()[i];
      for (std::size_t q = 0; q < e.size(); ++q) {
        if (q > 0 && e[q - 1].first == e[q].first) {  // a repeated neighbour: merged
          L.valuePtr()[at - 1] += e[q].second;
          continue;
        }
        L.innerIndexPtr()[at] = e[q].first;
        L.valuePtr()[at++] = e[q].second + (static_cast<std::size_t>(e[q].first) == i ? s : 0.0);
      }
    }
    done.done(r.size());
  });
  L.makeCompressed();
  return L;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> join_rows_both_ways(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                                                                 const std::vector<Eigen::Vector3d>& P,
                                                                 const std::vector<Eigen::Vector3d>& N,
                                                                 LaplacianScheme scheme, double t, double regularization,
                                                                 const std::vector<int>& points) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n || static_cast<std::size_t>(n) != P.size() || (!N.empty() && N.size() != P.size()))
    throw std::invalid_argument("the Laplacian has " + std::to_string(n) + " rows, the cloud " + std::to_string(P.size()) +
                                " points and " + std::to_string(N.size()) + " normals");
  std::vector<char> rebuilt(n, 0);
  for (int i : points) {
    if (i < 0 || i >= n)
      throw std::invalid_argument("point " + std::to_string(i) + " is outside the Laplacian's " + std::to_string(n) +
                                  " rows");
    rebuilt[i] = 1;
  }
  using RowIt = Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator;
  std::vector<std::vector<int>> both(n);  // the rebuilt rows' neighbours, both ways
  for (Eigen::Index i = 0; i < n; ++i)
    for (RowIt it(L, i); it; ++it) {
      const int j = static_cast<int>(it.col());
      if (j == i || it.value() == 0) continue;
      if (rebuilt[i]) both[i].push_back(j);
      if (rebuilt[j]) both[j].push_back(static_cast<int>(i));
    }
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(L.nonZeros()) + points.size() * 32);
  Eigen::VectorXd w;
  Eigen::Matrix2Xd D;
  std::vector<double> sq;
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<int>& nb = both[i];
    if (!rebuilt[i] || nb.empty()) {  // (a point no row joins to any other keeps its own)
      for (RowIt it(L, i); it; ++it) entries.emplace_back(static_cast<int>(i), static_cast<int>(it.col()), it.value());
      continue;
    }
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    const int k = static_cast<int>(nb.size());
    sq.resize(nb.size());
    for (int j = 0; j < k; ++j) sq[j] = (P[i] - P[nb[j]]).squaredNorm();
    // (the optimal scheme needs 3 neighbours; fewer get equal weights)
    row_weights(P, N, static_cast<std::size_t>(i), nb.data(), sq.data(), k,
                scheme == LaplacianScheme::Optimal && k < 3 ? LaplacianScheme::Uniform : scheme, t, regularization, w, D);
    double sum = w.sum();
    if (!(std::abs(sum) > 0)) w.setConstant(1.0), sum = k;  // heat kernel underflow, as build_laplacian
    double diagonal = 0;  // the weights' sum, so that the row sums to zero to the last bit
    for (int j = 0; j < k; ++j) {
      entries.emplace_back(static_cast<int>(i), nb[j], -w(j) / sum);
      diagonal += w(j) / sum;
    }
    entries.emplace_back(static_cast<int>(i), static_cast<int>(i), diagonal);
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> out(n, n);
  out.setFromTriplets(entries.begin(), entries.end());
  return out;
}

}  // namespace scallop
