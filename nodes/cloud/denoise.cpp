#include "nodes/cloud/denoise.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "nodes/cloud/knn.h"

namespace scallop {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Projection {
  Vector3d point, normal;
  bool moved = false;
};

// One MLS projection of q (= X[0]) given its neighbourhood X[0..m) with squared distances
// d2[0..m) from q (d2[0] = 0). h2 is the squared Gaussian width: weight exp(-d2 / h2).
// `up` orients the normal.
Projection project(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up) {
  Projection out;
  out.point = X[0];
  out.normal = up;
  if (m < 6 || !(h2 > 0)) return out;

  // Step 1: reference plane = weighted PCA (Alexa et al. 2003, eq. 3 with the plane's origin
  // freed). Weights theta(d) = exp(-d^2 / h^2), Gaussian as in Levin 2003.
  const Vector3d& q = X[0];
  double sw = 0;
  Vector3d c = Vector3d::Zero();
  thread_local std::vector<double> w;
  w.resize(m);
  for (int j = 0; j < m; ++j) {
    w[j] = std::exp(-d2[j] / h2);
    sw += w[j];
    c += w[j] * (X[j] - q);
  }
  c /= sw;
  Matrix3d C = Matrix3d::Zero();
  for (int j = 0; j < m; ++j) {
    const Vector3d r = X[j] - q - c;
    C.noalias() += w[j] * r * r.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(C);
  const Vector3d lambda = es.eigenvalues();  // ascending
  if (!(lambda(1) > 1e-12 * lambda(2))) return out;  // coincident or collinear points
  Vector3d n = es.eigenvectors().col(0);
  if (n.dot(up) < 0) n = -n;
  const Vector3d t1 = es.eigenvectors().col(2);
  const Vector3d t2 = n.cross(t1);

  // Step 2: weighted least squares for w = a + b s + c t + d s^2 + e s t + f t^2, with the frame
  // coordinates scaled by h (s = u / h, t = v / h) so that the 6x6 normal equations are well
  // scaled whatever the units.
  const double inv_h = 1.0 / std::sqrt(h2);
  Matrix6d A = Matrix6d::Zero();
  Vector6d rhs = Vector6d::Zero();
  for (int j = 0; j < m; ++j) {
    const Vector3d r = X[j] - q;
    const double s = r.dot(t1) * inv_h, t = r.dot(t2) * inv_h, z = r.dot(n);
    Vector6d phi;
    phi << 1, s, t, s * s, s * t, t * t;
    A.selfadjointView<Eigen::Lower>().rankUpdate(phi, w[j]);
    rhs += (w[j] * z) * phi;
  }
  A = A.selfadjointView<Eigen::Lower>();
  Eigen::LDLT<Matrix6d> ldlt(A);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-10)) return out;
  const Vector6d coef = ldlt.solve(rhs);
  if (!coef.allFinite()) return out;

  // Step 3: the quadric point above q, and the quadric's normal there (gradient (b, c) / h).
  out.point = q + coef(0) * n;
  out.normal = (n - coef(1) * inv_h * t1 - coef(2) * inv_h * t2).normalized();
  if (out.normal.dot(up) < 0) out.normal = -out.normal;
  out.moved = true;
  return out;
}

void check_input(const std::vector<Vector3d>& P, const std::vector<Vector3d>& N,
                 const DenoiseOptions& o, const Neighborhoods* nbrs) {
  if (P.empty()) throw std::invalid_argument("the cloud is empty");
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!P[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a NaN or infinite coordinate");
  if (!N.empty() && N.size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) + " points but " +
                                std::to_string(N.size()) + " normals");
  if (o.k < 5) throw std::invalid_argument("k must be at least 5 (got " + std::to_string(o.k) + ")");
  if (!std::isfinite(o.radius) || o.radius < 0)
    throw std::invalid_argument("radius must be finite and >= 0 (got " +
                                std::to_string(o.radius) + ")");
  if (o.iterations < 0)
    throw std::invalid_argument("iterations must be >= 0 (got " + std::to_string(o.iterations) + ")");
  if (nbrs) {
    if (nbrs->k < 1 || nbrs->size() != P.size() || nbrs->sq_dists.size() != nbrs->indices.size())
      throw std::invalid_argument("the neighbourhoods (" + std::to_string(nbrs->size()) +
                                  " points, k = " + std::to_string(nbrs->k) +
                                  ") do not match the cloud (" + std::to_string(P.size()) +
                                  " points)");
    for (int j : nbrs->indices)
      if (j < 0 || static_cast<std::size_t>(j) >= P.size())
        throw std::invalid_argument("a neighbour index (" + std::to_string(j) +
                                    ") is outside the cloud");
  }
}

}  // namespace

DenoiseResult mls_denoise(const std::vector<Vector3d>& P, const std::vector<Vector3d>& N,
                          const DenoiseOptions& o, const Neighborhoods* nbrs,
                          const std::function<void(double)>& progress) {
  check_input(P, N, o, nbrs);
  const std::size_t n = P.size();
  DenoiseResult res;
  res.points = P;
  res.normals.assign(n, Vector3d::UnitZ());
  if (!N.empty()) res.normals = N;

  const int k = nbrs ? std::min(o.k, nbrs->k)
                     : static_cast<int>(std::min<std::size_t>(o.k, n - 1));
  const double r2 = o.radius * o.radius;
  const int iterations = o.iterations;
  std::vector<Vector3d> next(n), next_normals(n);
  std::mutex progress_lock;

  struct Scratch {
    std::vector<int> idx;
    std::vector<double> d2;
    std::vector<Vector3d> pts;
    std::vector<double> pd2;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::vector<double> reach(n);  // distance from each point to its k-th neighbour (mm)

  for (int it = 0; it < iterations; ++it) {
    const std::vector<Vector3d>& X = res.points;
    std::unique_ptr<KnnIndex> index;
    if (!nbrs) index = std::make_unique<KnnIndex>(X);
    // The k neighbours of point i into s.idx / s.d2 (squared distances at the current positions).
    auto neighbours = [&](std::size_t i, Scratch& s) {
      if (index) {
        index->query(X[i], k, s.idx, s.d2, static_cast<int>(i));
      } else {
        const auto first = nbrs->indices.begin() + i * nbrs->k;
        s.idx.assign(first, first + k);
        s.d2.resize(k);
        for (int j = 0; j < k; ++j) s.d2[j] = (X[s.idx[j]] - X[i]).squaredNorm();
      }
    };
    // Automatic radius. Taking each point's own k-th neighbour distance would give a point on the
    // boundary of the cloud (half or a quarter of a disk around it) a neighbourhood 1.4 to 2 times
    // wider than inside, and the one-sided fit's bias grows with the cube of that width. The
    // smallest k-th neighbour distance over the neighbourhood is that of nearby interior points,
    // so it stays the interior's width on the boundary while following the local density.
    if (r2 == 0) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
        Scratch& s = scratch.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          neighbours(i, s);
          reach[i] = std::sqrt(*std::max_element(s.d2.begin(), s.d2.end()));
        }
      });
    }
    std::atomic<std::size_t> kept{0}, done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
      Scratch& s = scratch.local();
      std::size_t kept_here = 0;
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        neighbours(i, s);
        double R2 = r2;
        if (R2 == 0) {
          double R = reach[i];
          for (int j : s.idx) R = std::min(R, reach[j]);
          R2 = R * R;
        }
        // The point itself first, then its neighbours within R.
        s.pts.assign(1, X[i]);
        s.pd2.assign(1, 0.0);
        for (std::size_t j = 0; j < s.idx.size(); ++j) {
          if (s.d2[j] > R2) continue;
          s.pts.push_back(X[s.idx[j]]);
          s.pd2.push_back(s.d2[j]);
        }
        // Gaussian width h = R / sqrt(2): the weight at R is e^-2, so the fit is local but still
        // averages over most of the neighbourhood (measured: lower noise than h = R / 2 for the
        // same k, with no visible bias).
        static const double hdiv = getenv("HDIV") ? atof(getenv("HDIV")) : 2.0; const double h2 = R2 / hdiv;
        const Vector3d up = N.empty() ? Vector3d::UnitZ() : N[i];
        const Projection p =
            project(s.pts.data(), s.pd2.data(), static_cast<int>(s.pts.size()), h2, up);
        next[i] = p.point;
        next_normals[i] = p.moved ? p.normal : res.normals[i];
        if (!p.moved) ++kept_here;
      }
      kept += kept_here;
      const std::size_t d = done += range.size();
      // The callback need not be thread-safe: one thread reports at a time, the others skip.
      if (progress && progress_lock.try_lock()) {
        progress((it + static_cast<double>(d) / n) / iterations);
        progress_lock.unlock();
      }
    });
    res.points.swap(next);
    if (o.set_normals) res.normals.swap(next_normals);
    res.kept = kept;
  }
  if (!o.set_normals) res.normals.clear();
  if (o.set_normals && N.empty() && iterations == 0) res.normals.assign(n, Vector3d::UnitZ());
  return res;
}

}  // namespace scallop
