#include "nodes/cloud/denoise.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <tuple>

#include "nodes/cloud/knn.h"
#include "nodes/geom/cell_hash_3d.h"

namespace scallop {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

struct Projection {
  Vector3d point, normal;
  bool moved = false;
  double spread = 0;  // standard error of the projected point along the normal / noise sigma
  double residual_variance = -1;  // mm^2, the fit's residual variance (-1: not computed)
  double dof = 0;                 // its effective degrees of freedom
};

// Gaussian weights w[j] = exp(-d2[j] / h2) and the weighted PCA frame (t1, t2, n) of X[0..m)
// around q = X[0], n oriented along `up` (step 1 below). False for coincident or collinear points.
bool weighted_frame(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up,
                    std::vector<double>& w, Vector3d& n, Vector3d& t1, Vector3d& t2) {
  // Reference plane = weighted PCA (Alexa et al. 2003, eq. 3 with the plane's origin freed).
  // Weights theta(d) = exp(-d^2 / h^2), Gaussian as in Levin 2003.
  const Vector3d& q = X[0];
  double sw = 0;
  Vector3d c = Vector3d::Zero();
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
  if (!(lambda(1) > 1e-12 * lambda(2))) return false;
  n = es.eigenvectors().col(0);
  if (n.dot(up) < 0) n = -n;
  t1 = es.eigenvectors().col(2);
  t2 = n.cross(t1);
  return true;
}

// Bases of the local height w(s, t) at frame coordinates (s, t): the quadric
// a + b s + c t + d s^2 + e s t + f t^2 (6 terms) and the cubic, which adds s^3, s^2 t, s t^2 and
// t^3 (10 terms). Both start with 1, s, t, so coef(0) is the offset and coef(1), coef(2) the
// gradient at the centre whatever the degree.
template <int N>
Eigen::Matrix<double, N, 1> polynomial_basis(double s, double t) {
  static_assert(N == 6 || N == 10);
  Eigen::Matrix<double, N, 1> phi;
  if constexpr (N == 6) {
    phi << 1, s, t, s * s, s * t, t * t;
  } else {
    phi << 1, s, t, s * s, s * t, t * t, s * s * s, s * s * t, s * t * t, t * t * t;
  }
  return phi;
}

// The monomials s^a t^b up to twice the degree of polynomial_basis<N>: an entry (r, c) of a fit's
// normal matrix Phi^T W Phi is the weighted sum of one of them (the product of basis terms r and
// c), so a fit sums these moments, 28 for the cubic and 15 for the quadric, rather than each entry
// of the lower triangle, 55 and 21 (the noisy plane's denoising graph, 50 000 points, sigma 0.02:
// 7.84 -> 6.48 s of CPU, farm-bench, 6 pairs; the points the same to 1e-14 mm). Numbered by
// degree d = a + b, then by b: s^a t^b is number d (d + 1) / 2 + b, and the basis is the first N
// of them, each computed as polynomial_basis<N> computes it.
template <int N>
struct Monomials {
  static constexpr int kDegree = N == 6 ? 2 : 3;
  static constexpr int kCount = (2 * kDegree + 1) * (2 * kDegree + 2) / 2;
  static constexpr int number(int a, int b) { return (a + b) * (a + b + 1) / 2 + b; }
  // The powers (a, b) of basis term r.
  static constexpr std::pair<int, int> powers(int r) {
    int d = 0;
    while ((d + 1) * (d + 2) / 2 <= r) ++d;
    const int b = r - d * (d + 1) / 2;
    return {d - b, b};
  }
  // The number of the monomial that is basis term r times basis term c.
  static constexpr int product(int r, int c) {
    return number(powers(r).first + powers(c).first, powers(r).second + powers(c).second);
  }
  // m[0 .. kCount) = the monomials at (s, t): s^d from s^(d-1), and s^(d-b) t^b from s^(d-b) t^(b-1).
  static void at(double s, double t, double* m) {
    m[0] = 1;
    for (int d = 1; d <= 2 * kDegree; ++d) {
      const int first = d * (d + 1) / 2, below = (d - 1) * d / 2;
      m[first] = m[below] * s;
      for (int b = 1; b <= d; ++b) m[first + b] = m[below + b - 1] * t;
    }
  }
};

// The Gaussian-weighted least-squares polynomial w = coef . polynomial_basis<N>(s, t) of a
// neighbourhood in the PCA frame of its reference plane (steps 1 and 2 of the projection below).
template <int N>
struct PolynomialFit {
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  Vector3d n, t1, t2;    // the frame: normal (oriented along `up`) and tangents
  double inv_h = 0;      // frame coordinates are scaled by 1/h: s = u / h, t = v / h
  Matrix A;              // Phi^T W Phi
  Matrix B;              // Phi^T W^2 Phi, for the variance of the coefficients
  Vector rhs;            // Phi^T W z
  Eigen::LDLT<Matrix> ldlt;  // of A
  Vector coef;
  bool summed = false;   // A, B, rhs and the sums below filled (the frame was found)
  // sum w, sum w^2 and sum w z^2 over the points (z their offset along n): with rhs they give the
  // residual sum of squares without a second pass over the points (residual_variance)
  double sum_w = 0, sum_w2 = 0, sum_wzz = 0;
};

// Solves f's normal equations (A, rhs filled). False for a singular system.
template <int N>
bool solve_fit(PolynomialFit<N>& f) {
  f.ldlt.compute(f.A);
  if (f.ldlt.info() != Eigen::Success || !(f.ldlt.rcond() > 1e-10)) return false;
  f.coef = f.ldlt.solve(f.rhs);
  return f.coef.allFinite();
}

// The quadric's fit to the same points as the cubic c: its basis is the cubic's first 6 terms, so
// its sums are the leading blocks of the cubic's, the same to the last bit as a fit of its own.
bool leading_quadric(const PolynomialFit<10>& c, PolynomialFit<6>& q) {
  q.n = c.n, q.t1 = c.t1, q.t2 = c.t2, q.inv_h = c.inv_h;
  q.A = c.A.topLeftCorner<6, 6>();
  q.B = c.B.topLeftCorner<6, 6>();
  q.rhs = c.rhs.head<6>();
  q.sum_w = c.sum_w, q.sum_w2 = c.sum_w2, q.sum_wzz = c.sum_wzz;
  return solve_fit(q);
}

// Fits X[0..m) (squared distances d2[0..m) from X[0], Gaussian weights exp(-d2 / h2) into w).
// False for a degenerate neighbourhood (coincident or collinear points, a singular system).
template <int N>
bool fit_polynomial(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up,
                    std::vector<double>& w, PolynomialFit<N>& f) {
  using Vector = typename PolynomialFit<N>::Vector;
  // Step 1: reference plane.
  if (!weighted_frame(X, d2, m, h2, up, w, f.n, f.t1, f.t2)) return false;
  // Step 2: weighted least squares, with the frame coordinates scaled by h so that the normal
  // equations are well scaled whatever the units.
  f.inv_h = 1.0 / std::sqrt(h2);
  using Mono = Monomials<N>;
  std::array<double, Mono::kCount> mw{}, mw2{}, mono;  // sum w s^a t^b, sum w^2 s^a t^b
  f.rhs = Vector::Zero();
  f.sum_wzz = 0;
  for (int j = 0; j < m; ++j) {
    const Vector3d r = X[j] - X[0];
    const double z = r.dot(f.n), wj = w[j], wj2 = wj * wj, wz = wj * z;
    Mono::at(r.dot(f.t1) * f.inv_h, r.dot(f.t2) * f.inv_h, mono.data());
    for (int e = 0; e < Mono::kCount; ++e) mw[e] += wj * mono[e], mw2[e] += wj2 * mono[e];
    for (int e = 0; e < N; ++e) f.rhs[e] += wz * mono[e];
    f.sum_wzz += wz * z;
  }
  for (int c = 0; c < N; ++c)
    for (int r = c; r < N; ++r) {
      const int e = Mono::product(r, c);
      f.A(r, c) = f.A(c, r) = mw[e];
      f.B(r, c) = f.B(c, r) = mw2[e];
    }
  f.sum_w = mw[0], f.sum_w2 = mw2[0];
  f.summed = true;
  return solve_fit(f);
}

// The residual variance of the weighted polynomial fit f (as fit_polynomial gave it), an
// estimate of sigma^2 when the polynomial follows the surface, and its effective degrees of
// freedom. False when they are not defined (too few points for the weights).
template <int N>
bool residual_variance(const PolynomialFit<N>& f, double& var, double& dof) {
  const double sw = f.sum_w, sw2 = f.sum_w2;
  // sum w (z - phi . coef)^2 = sum w z^2 - coef . rhs, as A coef = rhs (a second pass over the
  // points was 6 % of denoising). The subtraction loses the digits by which the offsets z (the
  // surface's height over the fitted plane) exceed the residuals; a few of double's 16.
  const double ssr = std::max(0.0, f.sum_wzz - f.coef.dot(f.rhs));
  // E[sum w r^2] = sigma^2 tr(W (I - H)) with the hat matrix H = Phi A^-1 Phi^T W, and
  // tr(W H) = tr(A^-1 Phi^T W^2 Phi) = tr(A^-1 B).
  const double denom = sw - f.ldlt.solve(f.B).trace();
  dof = sw * sw / sw2 - N;
  if (!(denom > 0) || !(dof > 1)) return false;
  var = ssr / denom;
  return std::isfinite(var);
}

// The projection of q = X[0] onto the fit f.
template <int N>
Projection projection_of(const PolynomialFit<N>& f, const Vector3d& q, const Vector3d& up, bool with_variance) {
  Projection out;
  // The fitted offset a = e0^T A^-1 Phi^T W z: for independent noise of sigma along n its
  // variance is sigma^2 e0^T A^-1 B A^-1 e0 with B = Phi^T W^2 Phi.
  const typename PolynomialFit<N>::Vector g = f.ldlt.solve(PolynomialFit<N>::Vector::Unit(0));
  out.spread = std::sqrt(std::max(0.0, g.dot(f.B * g)));
  if (with_variance && !residual_variance(f, out.residual_variance, out.dof))
    out.residual_variance = -1;

  // Step 3: the polynomial's point above q, and its normal there (gradient (b, c) / h).
  out.point = q + f.coef(0) * f.n;
  out.normal = (f.n - f.coef(1) * f.inv_h * f.t1 - f.coef(2) * f.inv_h * f.t2).normalized();
  if (out.normal.dot(up) < 0) out.normal = -out.normal;
  out.moved = true;
  return out;
}

// One MLS projection of q (= X[0]) given its neighbourhood X[0..m) with squared distances
// d2[0..m) from q (d2[0] = 0), by a polynomial of N terms (polynomial_basis). h2 is the squared
// Gaussian width: weight exp(-d2 / h2). `up` orients the normal. With N = 10 and `quadric` given,
// the quadric's projection from the same points too (left unmoved when it is degenerate).
template <int N>
Projection project_with(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up,
                        bool with_variance, Projection* quadric) {
  Projection out;
  out.point = X[0];
  out.normal = up;
  if (quadric) *quadric = out;
  if (m < N || !(h2 > 0)) return out;
  thread_local std::vector<double> w;
  PolynomialFit<N> f;
  const bool fitted = fit_polynomial(X, d2, m, h2, up, w, f);
  if constexpr (N == 10) {
    PolynomialFit<6> q;
    if (quadric && f.summed && leading_quadric(f, q))
      *quadric = projection_of(q, X[0], up, with_variance);
  }
  return fitted ? projection_of(f, X[0], up, with_variance) : out;
}

// A fit kept to be evaluated at points other than its centre: the widest scales of the points
// around a centre are fitted once there (DenoiseOptions::share).
struct SharedFit {
  int terms = 0;  // 6 (quadric) or 10 (cubic); 0: none (a degenerate neighbourhood)
  Vector3d origin = Vector3d::Zero(), n = Vector3d::UnitZ(), t1 = Vector3d::UnitX(), t2 = Vector3d::UnitY();
  double inv_h = 0;
  Eigen::Matrix<double, 10, 1> coef = Eigen::Matrix<double, 10, 1>::Zero();
  // A^-1 B A^-1: the variance of the polynomial's value at basis phi is sigma^2 phi^T cov phi
  Eigen::Matrix<double, 10, 10> cov = Eigen::Matrix<double, 10, 10>::Zero();
  double residual_variance = -1, dof = 0;
  // the standard error at the centre / sigma, as projection_of gives it there
  double spread() const { return std::sqrt(std::max(0.0, cov(0, 0))); }
};

template <int N>
SharedFit shared_fit(const PolynomialFit<N>& f, const Vector3d& origin, bool with_variance) {
  SharedFit out;
  out.terms = N;
  out.origin = origin, out.n = f.n, out.t1 = f.t1, out.t2 = f.t2, out.inv_h = f.inv_h;
  out.coef.template head<N>() = f.coef;
  const typename PolynomialFit<N>::Matrix AinvB = f.ldlt.solve(f.B);
  out.cov.template topLeftCorner<N, N>() = f.ldlt.solve(AinvB.transpose());
  if (with_variance && !residual_variance(f, out.residual_variance, out.dof)) out.residual_variance = -1;
  return out;
}

// The projection of q onto the shared fit f: q moves along f's normal onto the polynomial above
// q's place in f's frame (projection_of, evaluated away from the centre).
template <int N>
Projection evaluate_shared(const SharedFit& f, const Vector3d& q, const Vector3d& up) {
  using Vector = Eigen::Matrix<double, N, 1>;
  const Vector3d r = q - f.origin;
  const double s = r.dot(f.t1) * f.inv_h, t = r.dot(f.t2) * f.inv_h;
  const Vector phi = polynomial_basis<N>(s, t);
  Vector ds, dt;  // d phi / ds, d phi / dt
  if constexpr (N == 6) {
    ds << 0, 1, 0, 2 * s, t, 0;
    dt << 0, 0, 1, 0, s, 2 * t;
  } else {
    ds << 0, 1, 0, 2 * s, t, 0, 3 * s * s, 2 * s * t, t * t, 0;
    dt << 0, 0, 1, 0, s, 2 * t, 0, s * s, 2 * s * t, 3 * t * t;
  }
  const Vector coef = f.coef.template head<N>();
  Projection out;
  out.point = q + (coef.dot(phi) - r.dot(f.n)) * f.n;
  out.normal = (f.n - coef.dot(ds) * f.inv_h * f.t1 - coef.dot(dt) * f.inv_h * f.t2).normalized();
  if (out.normal.dot(up) < 0) out.normal = -out.normal;
  out.spread = std::sqrt(std::max(0.0, phi.dot(f.cov.template topLeftCorner<N, N>() * phi)));
  out.residual_variance = f.residual_variance;
  out.dof = f.dof;
  out.moved = true;
  return out;
}

Projection evaluate_shared(const SharedFit& f, const Vector3d& q, const Vector3d& up) {
  if (f.terms == 10) return evaluate_shared<10>(f, q, up);
  if (f.terms == 6) return evaluate_shared<6>(f, q, up);
  Projection out;
  out.point = q;
  out.normal = up;
  return out;
}

// The fit project() makes of X[0..m), kept for sharing (terms 0 where project() would leave the
// point in place); with `quadric` given and the cubic summed, its leading quadric too.
SharedFit fit_for_sharing(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up, int degree,
                          bool with_variance, SharedFit* quadric = nullptr) {
  SharedFit out;
  if (quadric) *quadric = SharedFit{};
  thread_local std::vector<double> w;
  if (degree == 3 && m >= 10) {
    if (!(h2 > 0)) return out;
    PolynomialFit<10> f;
    const bool fitted = fit_polynomial(X, d2, m, h2, up, w, f);
    PolynomialFit<6> q;
    if (quadric && f.summed && leading_quadric(f, q)) *quadric = shared_fit(q, X[0], with_variance);
    if (fitted) out = shared_fit(f, X[0], with_variance);
    return out;
  }
  if (m < 6 || !(h2 > 0)) return out;
  PolynomialFit<6> f;
  if (fit_polynomial(X, d2, m, h2, up, w, f)) out = shared_fit(f, X[0], with_variance);
  return out;
}

// `degree` 2 or 3. A neighbourhood of fewer points than the cubic has coefficients is fitted by
// the quadric: the cubic would leave its point in place. Otherwise a point's scales all take its
// degree, so that nested fits differ by noise as the agreement test expects (with the quadric
// below 30 points and the cubic above, a noisy plane's points were narrowed by the mixed
// comparisons and their normals tilted 0.11 rad). With `quadric` given and the cubic fitted, the
// quadric's projection from the same points too.
Projection project(const Vector3d* X, const double* d2, int m, double h2, const Vector3d& up, int degree,
                   bool with_variance = false, Projection* quadric = nullptr) {
  return degree == 3 && m >= 10 ? project_with<10>(X, d2, m, h2, up, with_variance, quadric)
                                : project_with<6>(X, d2, m, h2, up, with_variance, nullptr);
}

// The residual variance of the weighted quadric fit to X[0..m) (see estimate_noise_sigma), and its
// effective degrees of freedom. False when the fit is degenerate.
bool fit_variance(const Vector3d* X, const double* d2, int m, double h2, double& var,
                  double& dof) {
  if (m < 10 || !(h2 > 0)) return false;
  thread_local std::vector<double> w;
  PolynomialFit<6> f;
  if (!fit_polynomial(X, d2, m, h2, Vector3d::UnitZ(), w, f)) return false;
  return residual_variance(f, var, dof);
}

void check_points(const std::vector<Vector3d>& P) {
  if (P.empty()) throw std::invalid_argument("the cloud is empty");
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!P[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a NaN or infinite coordinate");
}

void check_input(const std::vector<Vector3d>& P, const std::vector<Vector3d>& N,
                 const DenoiseOptions& o, const Neighborhoods* nbrs) {
  check_points(P);
  if (!N.empty() && N.size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) + " points but " +
                                std::to_string(N.size()) + " normals");
  if (o.k != 0 && o.k < 5)
    throw std::invalid_argument("k must be 0 (automatic) or at least 5 (got " +
                                std::to_string(o.k) + ")");
  if (o.k == 0 && !(std::isfinite(o.tolerance) && o.tolerance > 0))
    throw std::invalid_argument("tolerance must be finite and > 0 (got " +
                                std::to_string(o.tolerance) + ")");
  if (!std::isfinite(o.radius) || o.radius < 0)
    throw std::invalid_argument("radius must be finite and >= 0 (got " +
                                std::to_string(o.radius) + ")");
  if (o.degree != 2 && o.degree != 3)
    throw std::invalid_argument("degree must be 2 or 3 (got " + std::to_string(o.degree) + ")");
  if (o.widen < 1)
    throw std::invalid_argument("widen must be at least 1 (got " + std::to_string(o.widen) + ")");
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

double estimate_noise_sigma(const std::vector<Vector3d>& P, int k, int samples) {
  check_points(P);
  if (k < 10) throw std::invalid_argument("k must be at least 10 (got " + std::to_string(k) + ")");
  if (samples < 1)
    throw std::invalid_argument("samples must be at least 1 (got " + std::to_string(samples) + ")");
  const std::size_t n = P.size();
  if (n < 11) return 0;
  const KnnIndex index(P);
  const std::size_t count = std::min<std::size_t>(n, samples);
  // var < 0 marks a failed fit
  std::vector<double> var(count, -1), dof(count, 0);
  struct Scratch {
    std::vector<int> idx;
    std::vector<double> d2, pd2;
    std::vector<Vector3d> pts;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
    Scratch& s = scratch.local();
    for (std::size_t c = range.begin(); c != range.end(); ++c) {
      const std::size_t i = c * n / count;  // evenly spaced indices
      index.query(P[i], k, s.idx, s.d2, static_cast<int>(i));
      if (s.idx.empty()) continue;
      s.pts.assign(1, P[i]);
      s.pd2.assign(1, 0.0);
      for (std::size_t j = 0; j < s.idx.size(); ++j) {
        s.pts.push_back(P[s.idx[j]]);
        s.pd2.push_back(s.d2[j]);
      }
      // the denoiser's weights: exp(-2 d^2 / R^2), R the distance to the k-th neighbour
      const double h2 = *std::max_element(s.d2.begin(), s.d2.end()) / 2;
      fit_variance(s.pts.data(), s.pd2.data(), static_cast<int>(s.pts.size()), h2, var[c],
                   dof[c]);
    }
  });
  std::vector<double> v, d;
  for (std::size_t c = 0; c < count; ++c)
    if (var[c] >= 0) {
      v.push_back(var[c]);
      d.push_back(dof[c]);
    }
  if (v.empty()) return 0;
  auto median = [](std::vector<double>& x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  const double nu = median(d);
  const double chi2_median = std::pow(1 - 2 / (9 * nu), 3);  // of chi^2_nu / nu
  return std::sqrt(median(v) / chi2_median);
}

int choose_denoise_k(double sigma, double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance) || !(sigma >= 0))
    throw std::invalid_argument("choose_denoise_k needs sigma >= 0 and tolerance > 0");
  constexpr double c = 3;
  const double k = c * std::pow(sigma / tolerance, 2);
  return static_cast<int>(std::lround(std::clamp(k, 32.0, 512.0)));
}

namespace {
// The uncertainty's summary fields of a result whose points and uncertainty are final.
void summarize_uncertainty(DenoiseResult& res, int scales) {
  const std::vector<double>& u = res.uncertainty;
  std::size_t worst = 0;
  for (std::size_t i = 0; i < u.size(); ++i)
    if (u[i] > u[worst]) worst = i;
  std::vector<double> sorted = u;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  res.uncertainty_median = sorted[sorted.size() / 2];
  res.uncertainty_max = u[worst];
  res.uncertainty_max_at = res.points[worst];
  res.uncertainty_factor = uncertainty_factor(scales);
  res.bias_max = res.bias.empty() ? 0.0 : *std::max_element(res.bias.begin(), res.bias.end());
}
}  // namespace

namespace {
// The centre nearest p within sqrt(r2) (ties: the lower index), or -1; centres filed in `grid`.
long nearest_centre(const CellHash3& grid, const std::vector<Vector3d>& X, const Vector3d& p, double r2) {
  long best = -1;
  double best_d2 = r2;
  grid.near(p, static_cast<int>(std::ceil(std::sqrt(r2) / grid.cell())), [&](std::size_t c) {
    const double d2 = (X[c] - p).squaredNorm();
    if (d2 < best_d2 || (d2 == best_d2 && best >= 0 && static_cast<long>(c) < best)) best = static_cast<long>(c), best_d2 = d2;
  });
  return best;
}

// The centres of the shared fits and the points each serves (CSR: centre c's points are
// member[first[c] .. first[c + 1])).
struct CentreMembers {
  std::vector<std::size_t> centre, first, member;
};

// A point becomes a centre when no centre so far lies within share times its reach (its k-th
// neighbour's distance; at most 4 grid cells), the points taken in the cloud's order; then each
// point goes to its nearest centre, which lies within that.
CentreMembers share_centres(const std::vector<Vector3d>& X, const std::vector<double>& reach, double share) {
  std::vector<double> r = reach;
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  CellHash3 grid(std::max(share * r[r.size() / 2], 1e-9));
  // A point's radius in cells is capped (a point far sparser than the median, or a median of 0
  // from repeated points, would search a huge block): a smaller radius only makes more centres.
  constexpr double kMaxCells = 4;
  auto radius = [&](std::size_t i) { return std::min(share * reach[i], kMaxCells * grid.cell()); };
  CentreMembers out;
  std::vector<int> slot(X.size(), -1);
  for (std::size_t i = 0; i < X.size(); ++i) {
    const double within = radius(i);
    if (nearest_centre(grid, X, X[i], within * within) >= 0) continue;
    grid.add(X[i], i);
    slot[i] = static_cast<int>(out.centre.size());
    out.centre.push_back(i);
  }
  std::vector<int> of(X.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const double within = radius(i);
      const long c = nearest_centre(grid, X, X[i], within * within);
      of[i] = c < 0 ? slot[i] : slot[static_cast<std::size_t>(c)];  // none: i is a centre itself
    }
  });
  out.first.assign(out.centre.size() + 1, 0);
  for (int c : of) ++out.first[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 0; c < out.centre.size(); ++c) out.first[c + 1] += out.first[c];
  out.member.resize(X.size());
  std::vector<std::size_t> next(out.first.begin(), out.first.end() - 1);
  for (std::size_t i = 0; i < X.size(); ++i) out.member[next[static_cast<std::size_t>(of[i])]++] = i;
  return out;
}
}  // namespace

constexpr std::size_t kSharedScales = 3;  // DenoiseOptions::share: the widest three scales are shared
constexpr int kMaxWiden = 2;
constexpr int kCubicFromK = 64;  // DenoiseOptions::degree 3 applies from this k
constexpr double kCubicSpreadRatio = 1.1;  // and where its widest fit's standard error is within this of the quadric's
constexpr int kIsolationNeighbours = 32;  // a narrowed point with under a quarter of its 32 nearest narrowed is chance
constexpr int kMinScaleNeighbours = 16;  // the narrowest fit of the multi-scale rule
constexpr double kRefitAgreement = 2;  // how many noise widths a wider rim refit may move a point

DenoiseResult mls_denoise(const std::vector<Vector3d>& P, const std::vector<Vector3d>& N,
                          const DenoiseOptions& o, const Neighborhoods* nbrs,
                          const std::function<void(double)>& progress) {
  check_input(P, N, o, nbrs);
  const std::size_t n = P.size();
  DenoiseResult res;
  int k_wanted = o.k;
  if (k_wanted == 0) {
    res.noise_sigma = estimate_noise_sigma(P);
    if (res.noise_sigma < o.tolerance) {
      res.points = P;
      res.normals = N;
      res.skipped = true;
      // left as they are: each point is known as well as the noise lets it be (no fit, so no
      // bias and no noise shared between scales: the one-scale factor, whatever `scales` says)
      res.uncertainty.assign(n, std::max(kUncertaintyFloor, uncertainty_factor(1) * res.noise_sigma));
      summarize_uncertainty(res, 1);
      if (progress) progress(1.0);
      return res;
    }
    k_wanted = choose_denoise_k(res.noise_sigma, o.tolerance) * (o.scales > 1 ? o.widen : 1);
  }
  res.points = P;
  res.normals.assign(n, Vector3d::UnitZ());
  if (!N.empty()) res.normals = N;

  const int k = nbrs ? std::min(k_wanted, nbrs->k)
                     : static_cast<int>(std::min<std::size_t>(k_wanted, n - 1));
  res.k = k;
  // The cubic needs many points in its widest fit: from the few of a small k its normal is
  // noise (k = 16 on a noisy plane: normals tilted 67 degrees).
  const int degree = o.degree == 3 && k >= kCubicFromK ? 3 : 2;
  // Each point's degree, every scale of it and its refits alike: the cubic where it is about as
  // certain as the quadric (inside), the quadric where it is not (a one-sided neighbourhood at the
  // rim couples the cubic terms with the offset: with the cubic there the noisy plane's zig-zag
  // program left 0.059 mm at its rim, verify.py, against 0.044 with the quadric).
  std::vector<char> point_degree(n, static_cast<char>(degree));
  const double r2 = o.radius * o.radius;
  const int iterations = o.iterations;
  std::vector<Vector3d> next(n), next_normals(n);
  std::vector<double> spread(n, 0.0);

  struct Scratch {
    std::vector<int> idx;
    std::vector<double> d2;
    std::vector<Vector3d> pts;
    std::vector<double> pd2;
    double R2 = 0;  // squared radius of the last fit_point
    std::vector<Vector3d> sub_pts;
    std::vector<double> sub_pd2;
    std::vector<Projection> fits;  // fit_scales: one per scale
    std::vector<double> offsets;
    std::vector<std::pair<double, int>> by_distance;  // fit_point's wider neighbourhood
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::vector<double> reach(n);  // distance from each point to its k-th neighbour (mm)
  std::vector<double> reach2(n);  // its square, as the search gave it
  std::vector<double> bias(n, 0.0);  // bound on the kept fit's shape bias (mm)
  std::vector<int> chosen(n, 0);     // scales below the widest the kept fit is (0: the widest)
  if (o.scales > 1 && res.noise_sigma < 0) res.noise_sigma = estimate_noise_sigma(P);
  // The multi-scale rule's neighbour counts, narrowest first: k / 2^(S-1) (at least
  // kMinScaleNeighbours) ... k.
  const bool lack_of_fit = o.scales > 1 && o.misfit_z > 0;
  std::vector<int> ks{k};
  while (static_cast<int>(ks.size()) < o.scales && ks.back() / 2 >= kMinScaleNeighbours)
    ks.push_back(ks.back() / 2);
  std::reverse(ks.begin(), ks.end());

  for (int it = 0; it < iterations; ++it) {
    const std::vector<Vector3d>& X = res.points;
    std::unique_ptr<KnnIndex> index;
    if (!nbrs) index = std::make_unique<KnnIndex>(X);
    // The k neighbours of point i into s.idx / s.d2 (squared distances at the current positions).
    auto neighbours = [&](std::size_t i, Scratch& s) {
      if (index && r2 == 0) {  // the radius is known: reach2[i]
        // a fit sums over its neighbours: their order does not matter
        index->query_within(X[i], reach2[i], k, s.idx, s.d2, static_cast<int>(i), false);
      } else if (index) {
        index->query(X[i], k, s.idx, s.d2, static_cast<int>(i));
      } else {
        const auto first = nbrs->indices.begin() + i * nbrs->k;
        s.idx.assign(first, first + k);
        s.d2.resize(k);
        for (int j = 0; j < k; ++j) s.d2[j] = (X[s.idx[j]] - X[i]).squaredNorm();
      }
    };
    // The m nearest neighbours of point i into s.idx / s.d2 (m <= k when the neighbourhoods are given).
    auto nearest = [&](std::size_t i, int m, Scratch& s) {
      if (index) {
        index->query(X[i], m, s.idx, s.d2, static_cast<int>(i));
      } else {
        const auto first = nbrs->indices.begin() + i * nbrs->k;
        s.idx.assign(first, first + std::min(m, nbrs->k));
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
          if (index) {
            // the previous point's reach, a little wider, as the guess: the points come in
            // space-filling order (cloud.clean), so it is a neighbour's
            const double guess = i > range.begin() ? 1.3 * reach2[i - 1] : 0.0;
            reach2[i] = index->kth_sq_distance(X[i], k, static_cast<int>(i), guess);
            reach[i] = std::sqrt(reach2[i]);
            continue;
          }
          neighbours(i, s);
          reach[i] = s.d2.empty() ? 0.0 : std::sqrt(*std::max_element(s.d2.begin(), s.d2.end()));
        }
      });
    }
    // The projection of point i from its `kk` nearest neighbours (kk > k: a wider neighbourhood,
    // the radius grown by sqrt(kk / k), so as many points again count on a one-sided rim).
    // Point i's `kk` nearest neighbours within its radius into s.pts / s.pd2 (the point itself
    // first), and the radius's square, grown by kk / k, into s.R2.
    auto gather = [&](std::size_t i, Scratch& s, int kk) {
      if (kk == k) {
        neighbours(i, s);
      } else {
        if (!index) throw std::logic_error("fit_point: no index for a wider neighbourhood");
        // the kk nearest in no order, searched first within the k nearest's reach grown as the
        // area they cover (a guess: the same points either way)
        const double guess = reach2[i] > 0 ? 1.3 * reach2[i] * kk / k : 0.0;
        const double kth = index->kth_sq_distance(X[i], kk, static_cast<int>(i), guess);
        index->query_within(X[i], kth, kk, s.idx, s.d2, static_cast<int>(i), false);
        // the k nearest of them first (by distance, then index, as a search of k gives them):
        // the radius below is taken over those
        s.by_distance.resize(s.idx.size());
        for (std::size_t j = 0; j < s.idx.size(); ++j) s.by_distance[j] = {s.d2[j], s.idx[j]};
        if (static_cast<std::size_t>(k) < s.by_distance.size())
          std::nth_element(s.by_distance.begin(), s.by_distance.begin() + k, s.by_distance.end());
        for (std::size_t j = 0; j < s.idx.size(); ++j) std::tie(s.d2[j], s.idx[j]) = s.by_distance[j];
      }
      double R2 = r2;
      if (R2 == 0) {
        double R = reach[i];
        for (int j = 0; j < std::min<int>(k, static_cast<int>(s.idx.size())); ++j)
          R = std::min(R, reach[s.idx[j]]);
        R2 = R * R;
      }
      R2 *= static_cast<double>(kk) / k;
      s.R2 = R2;
      // The point itself first, then its neighbours within R.
      s.pts.assign(1, X[i]);
      s.pd2.assign(1, 0.0);
      for (std::size_t j = 0; j < s.idx.size(); ++j) {
        if (s.d2[j] > R2) continue;
        s.pts.push_back(X[s.idx[j]]);
        s.pd2.push_back(s.d2[j]);
      }
    };
    auto fit_point = [&](std::size_t i, Scratch& s, int kk, Projection* quadric = nullptr) {
      gather(i, s, kk);
      // Gaussian width h = R / sqrt(2): the weight at R is e^-2, so the fit is local but still
      // averages over most of the neighbourhood (measured: lower noise than h = R / 2 for the
      // same k, with no visible bias).
      const Vector3d up = N.empty() ? Vector3d::UnitZ() : N[i];
      return project(s.pts.data(), s.pd2.data(), static_cast<int>(s.pts.size()), s.R2 / 2, up, point_degree[i],
                     lack_of_fit, quadric);
    };
    // The projection of point i from the narrower neighbourhood of radius R sqrt(kk / k), the
    // subset of the one fit_point(i, s, k) has just gathered into s.
    auto subset = [&](Scratch& s, int kk) {
      const double R2 = s.R2 * kk / k;
      s.sub_pts.clear();
      s.sub_pd2.clear();
      for (std::size_t j = 0; j < s.pts.size(); ++j)
        if (s.pd2[j] <= R2) {
          s.sub_pts.push_back(s.pts[j]);
          s.sub_pd2.push_back(s.pd2[j]);
        }
      return R2;
    };
    auto fit_subset = [&](std::size_t i, Scratch& s, int kk) {
      const double R2 = subset(s, kk);
      const Vector3d up = N.empty() ? Vector3d::UnitZ() : N[i];
      return project(s.sub_pts.data(), s.sub_pd2.data(), static_cast<int>(s.sub_pts.size()), R2 / 2, up,
                     point_degree[i], lack_of_fit);
    };
    auto store = [&](std::size_t i, const Projection& p) {
      next[i] = p.point;
      next_normals[i] = p.moved ? p.normal : res.normals[i];
      spread[i] = p.moved ? p.spread : 1.0;  // a point left in place keeps its own noise
    };
    // The scale of point i by a Lepski-type rule (Lepski, Mammen, Spokoiny, Ann. Statist. 1997;
    // Katkovnik's intersection of confidence intervals): fits from k / 2^(S-1) (at least
    // kMinScaleNeighbours) up to k neighbours, nested, each one's offset a_j along the widest
    // fit's normal. A wider fit j is kept while it agrees with every narrower one i within what
    // noise explains: |a_j - a_i| <= gamma sigma sqrt(spread_i^2 - spread_j^2) (the nested fits'
    // difference has that spread). Where the shape is sharp for the neighbourhood (a crest, a
    // crease) the wider fits are biased off the narrower ones and a narrower, noisier, but
    // unbiased fit is kept.
    // The bias the kept fit may still carry is bounded from every other scale: a quadric fit's
    // bias grows at least as the cube of its radius, i.e. by 2^1.5 per doubling of k, so
    // against a narrower fit m scales down  bias <= |a_keep - a_i| / (1 - 2^(-1.5 m)),
    // against a wider one m scales up       bias <= |a_j - a_keep| / (2^(1.5 m) - 1).
    // The difference is not reduced by the noise it may hold: noise shared by nested fits can
    // hide a bias as well as fake one (measured on noisy crests: subtracting it left points 1.7
    // times their bound off the surface). Only the bias_scales narrower fits next to the kept one
    // count: the narrowest are so noisy that their differences, not any bias, set the bound
    // (median uncertainty of a noisy plane 0.0156 with all six, 0.0104 with three, k = 1200).
    // Where a crest lies inside every wide fit, their biases are alike (no longer growing as
    // the cube of the radius) and they agree; their residuals do not: a wider fit is kept only
    // if its residual variance passes a lack-of-fit test against sigma^2, within misfit_z of
    // its spread sqrt(2 / dof) (measured on a noisy crest of slope 0.3, radius 3 mm, k = 1200:
    // largest |error| / uncertainty 1.21 without the test, 0.90 with it).
    auto choose_scale = [&](std::size_t i, Scratch& s) -> Projection {
      const std::vector<Projection>& fits = s.fits;
      const Projection& widest = fits.back();
      std::vector<double>& a = s.offsets;
      a.resize(ks.size());
      for (std::size_t j = 0; j < ks.size(); ++j) a[j] = (fits[j].point - X[i]).dot(widest.normal);
      const double sigma = std::max(0.0, res.noise_sigma);
      std::size_t keep = ks.size();  // none yet
      for (std::size_t j = 0; j < ks.size(); ++j) {
        if (!fits[j].moved) continue;
        bool agrees = true;
        for (std::size_t i2 = 0; i2 < j && agrees; ++i2) {
          if (!fits[i2].moved) continue;
          const double noise = sigma * std::sqrt(std::max(0.0, fits[i2].spread * fits[i2].spread -
                                                                  fits[j].spread * fits[j].spread));
          agrees = std::abs(a[j] - a[i2]) <= o.ici_gamma * noise;
        }
        // and a wider fit must follow the surface as well as noise lets it: its residual
        // variance within the upper misfit_z quantile of sigma^2 chi^2_nu / nu (Wilson-Hilferty;
        // the normal approximation 1 + z sqrt(2 / nu) narrowed a few % of a noisy plane's
        // points by chance at its few-neighbour scales, each then 3 to 10 times less certain)
        if (agrees && lack_of_fit && keep != ks.size() && fits[j].residual_variance >= 0) {
          const double nu = fits[j].dof, c = 2 / (9 * nu);
          agrees = fits[j].residual_variance <=
                   sigma * sigma * std::pow(1 - c + o.misfit_z * std::sqrt(c), 3);
        }
        if (!agrees) break;
        keep = j;
      }
      if (keep == ks.size()) return widest;
      double b = 0;
      for (std::size_t j = 0; j < ks.size(); ++j) {
        if (j == keep || !fits[j].moved) continue;
        const double m = std::abs(static_cast<double>(j) - static_cast<double>(keep));
        if (j < keep && o.bias_scales > 0 && m > o.bias_scales) continue;
        const double growth = std::pow(2.0, o.bias_growth * m);
        b = std::max(b, std::abs(a[j] - a[keep]) / (j < keep ? 1 - 1 / growth : growth - 1));
      }
      bias[i] = b;
      chosen[i] = static_cast<int>(ks.size() - 1 - keep);
      return fits[keep];
    };
    auto fit_scales = [&](std::size_t i, Scratch& s) -> Projection {
      Projection quadric;  // the quadric's widest fit, from the cubic's sums
      Projection widest = fit_point(i, s, k, point_degree[i] == 3 ? &quadric : nullptr);
      if (quadric.moved && !(widest.moved && widest.spread <= kCubicSpreadRatio * quadric.spread)) {
        point_degree[i] = 2;
        widest = quadric;
      }
      bias[i] = 0;
      chosen[i] = 0;
      if (ks.size() == 1 || !widest.moved) return widest;
      std::vector<Projection>& fits = s.fits;
      fits.resize(ks.size());
      fits.back() = widest;
      for (std::size_t j = 0; j + 1 < ks.size(); ++j) fits[j] = fit_subset(i, s, ks[j]);
      return choose_scale(i, s);
    };
    // Shared wide fits: the widest kSharedScales scales change little from one point to the next
    // (their neighbourhoods nearly the same points), so they are fitted once at centres share R
    // apart and each point evaluates those of its nearest centre at itself (evaluate_shared: its
    // standard error there counts the distance from the centre). The narrower scales, which a
    // crest or a rim changes within a spacing, stay each point's own. Centre by centre: its fits,
    // then its points (the fits are dropped after them).
    const bool sharing = o.share > 0 && index && r2 == 0 && ks.size() > kSharedScales;
    struct CentreFits {
      SharedFit fits[kSharedScales];  // the shared scales, narrowest first
      int degree = 2;
      double R2 = 0;                  // the centre's squared radius (widest scale)
    };
    auto fit_centre = [&](std::size_t i, Scratch& s, CentreFits& cf) {
      gather(i, s, k);
      cf.R2 = s.R2;
      const Vector3d up = N.empty() ? Vector3d::UnitZ() : N[i];
      SharedFit quadric;
      SharedFit widest = fit_for_sharing(s.pts.data(), s.pd2.data(), static_cast<int>(s.pts.size()), s.R2 / 2, up,
                                         point_degree[i], lack_of_fit, point_degree[i] == 3 ? &quadric : nullptr);
      cf.degree = point_degree[i];
      // the cubic where it is about as certain as the quadric, as fit_scales decides it
      if (quadric.terms && !(widest.terms && widest.spread() <= kCubicSpreadRatio * quadric.spread())) {
        cf.degree = 2;
        widest = quadric;
      }
      cf.fits[kSharedScales - 1] = widest;
      for (std::size_t j = 0; j + 1 < kSharedScales; ++j) {
        const double R2 = subset(s, ks[ks.size() - kSharedScales + j]);
        cf.fits[j] = fit_for_sharing(s.sub_pts.data(), s.sub_pd2.data(), static_cast<int>(s.sub_pts.size()), R2 / 2,
                                     up, cf.degree, lack_of_fit);
      }
    };
    // Point i from its centre's shared fits and its own narrower ones; its own fits at every scale
    // where the centre's widest is degenerate.
    auto fit_scales_shared = [&](std::size_t i, Scratch& s, const CentreFits& cf) -> Projection {
      if (!cf.fits[kSharedScales - 1].terms) return fit_scales(i, s);
      const Vector3d up = N.empty() ? Vector3d::UnitZ() : N[i];
      point_degree[i] = static_cast<char>(cf.degree);
      bias[i] = 0;
      chosen[i] = 0;
      std::vector<Projection>& fits = s.fits;
      fits.resize(ks.size());
      const std::size_t own = ks.size() - kSharedScales;
      for (std::size_t j = 0; j < kSharedScales; ++j) fits[own + j] = evaluate_shared(cf.fits[j], X[i], up);
      // its own neighbours within the widest own scale's radius (the centre's R, as its subsets)
      s.R2 = cf.R2;
      index->query_within(X[i], cf.R2 * ks[own - 1] / k, static_cast<int>(n), s.idx, s.d2, static_cast<int>(i), false);
      s.pts.assign(1, X[i]);
      s.pd2.assign(1, 0.0);
      for (std::size_t j = 0; j < s.idx.size(); ++j) {
        s.pts.push_back(X[s.idx[j]]);
        s.pd2.push_back(s.d2[j]);
      }
      for (std::size_t j = 0; j < own; ++j) fits[j] = fit_subset(i, s, ks[j]);
      return choose_scale(i, s);
    };
    std::atomic<std::size_t> kept{0};
    ParallelProgress done(progress, n, static_cast<double>(it) / iterations,
                          static_cast<double>(it + 1) / iterations);
    if (sharing) {
      const CentreMembers centres = share_centres(X, reach, o.share);
      res.shared_centres = centres.centre.size();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.centre.size(), 4), [&](const auto& range) {
        Scratch& s = scratch.local();
        std::size_t kept_here = 0, points = 0;
        CentreFits cf;
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
          fit_centre(centres.centre[c], s, cf);
          for (std::size_t m = centres.first[c]; m < centres.first[c + 1]; ++m) {
            const std::size_t i = centres.member[m];
            const Projection p = fit_scales_shared(i, s, cf);
            store(i, p);
            if (!p.moved) ++kept_here;
            ++points;
          }
        }
        kept += kept_here;
        done.done(points);
      });
    } else {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
        Scratch& s = scratch.local();
        std::size_t kept_here = 0;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const Projection p = fit_scales(i, s);
          store(i, p);
          if (!p.moved) ++kept_here;
        }
        kept += kept_here;
        done.done(range.size());
      });
    }
    // A point narrowed nearly alone, under a quarter of its kIsolationNeighbours nearest
    // narrowed with it, is chance: the neighbourhoods of nearby points overlap it almost wholly,
    // so a shape the wide fit misses would narrow them too (a crest narrows a band, whose edge
    // still has half its neighbours narrowed). Chance narrowings (4-sigma disagreements, in
    // clusters of 2 to 5 points around an extreme sample: 17 points of a 50 000-point noisy
    // plane) keep a fit 2 to 8 times less certain, and each leaves stock for the planner
    // around it; such a point keeps the widest fit instead, with the median bias bound of its
    // neighbours (the largest, itself a noisy difference, left them 0.03-0.05 mm uncertain).
    if (ks.size() > 1) {
      std::vector<std::size_t> narrowed;
      for (std::size_t i = 0; i < n; ++i)
        if (chosen[i] > 0) narrowed.push_back(i);
      if (!narrowed.empty() && !index && !nbrs) index = std::make_unique<KnnIndex>(X);
      // chosen and bias change only after this loop, so every point sees the same neighbours
      std::vector<char> isolated(narrowed.size(), 0);
      std::vector<double> neighbour_bias(narrowed.size(), 0.0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, narrowed.size(), 16), [&](const auto& range) {
        Scratch& s = scratch.local();
        for (std::size_t r = range.begin(); r != range.end(); ++r) {
          const std::size_t i = narrowed[r];
          nearest(i, kIsolationNeighbours, s);
          isolated[r] = 4 * std::count_if(s.idx.begin(), s.idx.end(), [&](int j) { return chosen[j] > 0; }) <
                        static_cast<std::ptrdiff_t>(s.idx.size());
          if (!isolated[r]) continue;
          s.offsets.clear();
          for (int j : s.idx) s.offsets.push_back(bias[j]);
          if (!s.offsets.empty()) {  // the upper median: each bound is itself a noisy difference
            std::nth_element(s.offsets.begin(), s.offsets.begin() + s.offsets.size() / 2, s.offsets.end());
            neighbour_bias[r] = s.offsets[s.offsets.size() / 2];
          }
          const Projection p = fit_point(i, s, k);
          if (p.moved) store(i, p);
        }
      });
      for (std::size_t r = 0; r < narrowed.size(); ++r)
        if (isolated[r]) {
          bias[narrowed[r]] = neighbour_bias[r];
          chosen[narrowed[r]] = 0;
          ++res.unnarrowed;
        }
    }
    // Near the rim of the cloud the neighbourhood is one-sided: half (a quarter at a corner) of
    // the points, and an offset extrapolated to the edge of the fit, so the projected point is
    // 1.5 to 4 times less certain than inside (measured standard errors, sigma = 0.02 mm, k = 301:
    // 0.0026 mm inside, up to 0.012 mm at the corners of a plane). Such points are refitted from
    // twice as many neighbours (kMaxWiden; 4 times changed nothing on the noisy waves' rim, where
    // 2 831 of 3 224 such refits are refused as biased) when that brings their standard error
    // nearer the median.
    if (o.equalize_rim && n > static_cast<std::size_t>(2 * k)) {
      std::vector<double> sorted;
      for (std::size_t i = 0; i < n; ++i)
        if (spread[i] < 1.0) sorted.push_back(spread[i]);
      if (!sorted.empty()) {
        std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
        const double target = 1.15 * sorted[sorted.size() / 2];
        std::vector<std::size_t> rim;
        for (std::size_t i = 0; i < n; ++i)
          if (spread[i] > target && spread[i] < 1.0 && chosen[i] == 0) rim.push_back(i);
        if (!rim.empty() && !index) index = std::make_unique<KnnIndex>(X);
        if (!rim.empty() && res.noise_sigma < 0) res.noise_sigma = estimate_noise_sigma(P);
        const double sigma = res.noise_sigma;
        std::atomic<std::size_t> biased{0};
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rim.size(), 16), [&](const auto& range) {
          Scratch& s = scratch.local();
          for (std::size_t r = range.begin(); r != range.end(); ++r) {
            const std::size_t i = rim[r];
            for (int m = 2; m <= kMaxWiden && spread[i] > target; ++m) {
              const int kk = static_cast<int>(std::min<std::size_t>(n - 1, std::size_t(m) * k));
              const Projection p = fit_point(i, s, kk);
              if (!p.moved || !(p.spread < spread[i])) continue;
              // The wider one-sided fit is less noisy but more biased where the rim is curved
              // (bias grows with the cube of the width). Noise alone moves it off the narrower
              // fit by about sigma * sqrt(spread_narrow^2 - spread_wide^2) (nested least
              // squares); a larger move is bias, and the narrower, honestly less certain, fit stays.
              const double noise = sigma * std::sqrt(spread[i] * spread[i] - p.spread * p.spread);
              if (std::abs((p.point - next[i]).dot(next_normals[i])) > kRefitAgreement * noise) {
                ++biased;
                break;
              }
              store(i, p);
            }
          }
        });
        res.refitted += rim.size();
        res.refits_biased += biased;
      }
    }
    res.points.swap(next);
    if (o.set_normals) res.normals.swap(next_normals);
    res.kept = kept;
  }
  if (!o.set_normals) res.normals.clear();
  if (res.noise_sigma < 0) res.noise_sigma = estimate_noise_sigma(P);
  res.standard_error.resize(n);
  for (std::size_t i = 0; i < n; ++i) res.standard_error[i] = res.noise_sigma * spread[i];
  res.bias = bias;
  res.uncertainty.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    res.uncertainty[i] = std::max(kUncertaintyFloor, uncertainty_factor(o.scales) * res.standard_error[i] + bias[i]);
    if (chosen[i] > 0) ++res.narrowed;
  }
  summarize_uncertainty(res, o.scales);
  double moved = 0;
  for (std::size_t i = 0; i < n; ++i) moved += (res.points[i] - P[i]).squaredNorm();
  res.moved_rms = std::sqrt(moved / n);
  return res;
}

}  // namespace scallop
