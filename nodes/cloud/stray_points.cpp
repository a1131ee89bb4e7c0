#include "nodes/cloud/stray_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "nodes/geom/tangent_frame.h"

namespace scallop {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}

std::vector<std::uint8_t> stray_points(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nb,
                                       std::vector<double>* off) {
  if (nb.size() != P.size())
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(nb.size()) + " points but the cloud has " +
                                std::to_string(P.size()));
  if (nb.k < 8) throw std::invalid_argument("stray points need at least 8 neighbours per point (got " + std::to_string(nb.k) + ")");
  std::vector<std::uint8_t> stray(P.size(), 0);
  // each point's distance from its neighbours' quadric and their rms residual from it (NaN where
  // nothing judges it)
  std::vector<double> dist_of(P.size(), NAN), rms_of(P.size(), NAN);
  if (off) off->assign(P.size(), 0.0);
  const int k = nb.k;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Eigen::Vector3d> local(k);
    std::vector<double> reach(k), residual(k), abs_residual(k);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      for (int j = 0; j < k; ++j) reach[j] = nb.sq_dist(nb.index(i, j), k - 1);
      std::nth_element(reach.begin(), reach.begin() + k / 2, reach.end());
      if (nb.sq_dist(i, k - 1) > kStrayIsolation * kStrayIsolation * reach[k / 2]) {
        stray[i] = 1;
        if (off) (*off)[i] = std::sqrt(nb.sq_dist(i, 0));
        continue;
      }
      // the neighbours' best-fit plane
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int j = 0; j < k; ++j) c += P[nb.index(i, j)];
      c /= k;
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (int j = 0; j < k; ++j) {
        const Eigen::Vector3d d = P[nb.index(i, j)] - c;
        C += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(C);
      const Eigen::Vector3d n = eig.eigenvectors().col(0);
      Eigen::Vector3d t1, t2;
      tangent_frame(n, t1, t2);
      // the quadric w = q(u, v) over it, by the normal equations; fitted again without the
      // neighbours it misfits by more than 4 robust deviations (another stray point among them)
      auto basis = [](double u, double v) {
        Eigen::Matrix<double, 6, 1> m;
        m << 1, u, v, u * u, u * v, v * v;
        return m;
      };
      for (int j = 0; j < k; ++j) {
        const Eigen::Vector3d d = P[nb.index(i, j)] - c;
        local[j] = {d.dot(t1), d.dot(t2), d.dot(n)};
      }
      Eigen::Matrix<double, 6, 1> q = Eigen::Matrix<double, 6, 1>::Zero();
      double spread = kInfinity;  // residuals beyond this are left out of the fit
      double rms = 0;
      bool fitted = false;
      for (int pass = 0; pass < 2; ++pass) {
        Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
        Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
        int used = 0;
        for (int j = 0; j < k; ++j) {
          if (pass > 0 && std::abs(residual[j]) > spread) continue;
          const auto m = basis(local[j].x(), local[j].y());
          A += m * m.transpose();
          b += m * local[j].z();
          ++used;
        }
        if (used < 8 || (pass > 0 && used == k)) break;  // (none left out: the same fit)
        const Eigen::Matrix<double, 6, 1> next = A.ldlt().solve(b);
        if (!next.allFinite()) break;
        q = next, fitted = true;
        double rss = 0;
        for (int j = 0; j < k; ++j) {
          residual[j] = local[j].z() - basis(local[j].x(), local[j].y()).dot(q);
          abs_residual[j] = std::abs(residual[j]);
          if (pass == 0 || abs_residual[j] <= spread) rss += residual[j] * residual[j];
        }
        rms = std::sqrt(rss / used);
        std::nth_element(abs_residual.begin(), abs_residual.begin() + k / 2, abs_residual.end());
        spread = 4 * 1.4826 * abs_residual[k / 2];
      }
      if (!fitted) continue;  // neighbours on a line: nothing to judge by
      const Eigen::Vector3d d = P[i] - c;
      const double dist = std::abs(d.dot(n) - basis(d.dot(t1), d.dot(t2)).dot(q));
      if (off) (*off)[i] = dist;
      dist_of[i] = dist, rms_of[i] = rms;
    }
  });
  // The cloud's noise, as the median neighbourhood sees it: a few neighbourhoods of a noisy cloud
  // misfit less than their share (16 points, 6 coefficients), and their 8 rms would drop good
  // points (40 of the noisy catalog plane's 50 000).
  std::vector<double> judged;
  for (double v : rms_of)
    if (!std::isnan(v)) judged.push_back(v);
  double noise = 0;
  if (!judged.empty()) {
    std::nth_element(judged.begin(), judged.begin() + judged.size() / 2, judged.end());
    noise = judged[judged.size() / 2];
  }
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!std::isnan(dist_of[i]))
      stray[i] = dist_of[i] > std::max(kStrayNoise * std::max(rms_of[i], noise),
                                       kStraySpacing * std::sqrt(nb.sq_dist(i, nb.k - 1)));
  return stray;
}

}  // namespace scallop
