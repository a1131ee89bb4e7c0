#include "nodes/geom/crease_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>

namespace scallop {

namespace {
constexpr double kLeastUp = 0.5;  // cos 60 degrees: a plane's normal against up
constexpr std::size_t kSidePoints = 3;
constexpr int kRounds = 2;  // the crease line's direction from the seeds, then from the planes found

// A least-squares plane from the points' count, sum and sum of outer products (about a common
// origin): its normal (turned toward up), a point on it and its sum of squared distances.
struct Plane {
  Eigen::Vector3d normal, point;
  double squares = INFINITY;
};
std::optional<Plane> plane_of(double count, const Eigen::Vector3d& sum, const Eigen::Matrix3d& outer,
                              const Eigen::Vector3d& up) {
  const Eigen::Vector3d c = sum / count;
  const Eigen::Matrix3d C = outer - count * c * c.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  if (es.info() != Eigen::Success || !(es.eigenvalues()[1] > 1e-12 * es.eigenvalues()[2])) return std::nullopt;
  Eigen::Vector3d n = es.eigenvectors().col(0);
  if (n.dot(up) < 0) n = -n;
  return Plane{n, c, std::max(0.0, es.eigenvalues()[0])};
}
}  // namespace

std::array<double, 2> CreaseSurface::plane_heights(const Eigen::Vector3d& x) const {
  // x + t up meets plane i at t = (offset_i - n_i·x) / (n_i·up).
  return {(offset[0] - normal[0].dot(x)) / normal[0].dot(up), (offset[1] - normal[1].dot(x)) / normal[1].dot(up)};
}

double CreaseSurface::height(const Eigen::Vector3d& x) const {
  const auto [t0, t1] = plane_heights(x);
  return ridge ? std::min(t0, t1) : std::max(t0, t1);
}

std::pair<double, double> CreaseSurface::extremes_over(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                       const Eigen::Vector3d& c) const {
  // Which side of the crease x lies on: the difference of the two planes' heights, affine in x.
  const auto side = [&](const Eigen::Vector3d& x) {
    const auto [t0, t1] = plane_heights(x);
    return t0 - t1;
  };
  double above = -INFINITY, below = -INFINITY;
  const auto at = [&](const Eigen::Vector3d& x) {
    const double h = height(x);
    above = std::max(above, h);
    below = std::max(below, -h);
  };
  const std::array<const Eigen::Vector3d*, 3> corner{&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d &p = *corner[k], &q = *corner[(k + 1) % 3];
    at(p);
    const double sp = side(p), sq = side(q);
    if ((sp < 0 && sq > 0) || (sp > 0 && sq < 0)) at(p + sp / (sp - sq) * (q - p));
  }
  return {above, below};
}

std::optional<CreaseSurface> fit_crease_surface(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& up,
                                                const std::array<Eigen::Vector3d, 2>& seed_normal) {
  const std::size_t n = points.size();
  if (n < kSidePoints) return std::nullopt;
  CreaseSurface s;
  s.up = up.normalized();
  const Eigen::Vector3d origin = points[0];  // sums about a point among them, for rounding
  Eigen::Vector3d sum_all = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer_all = Eigen::Matrix3d::Zero();
  for (const auto& p : points) sum_all += p - origin, outer_all += (p - origin) * (p - origin).transpose();
  const auto one = plane_of(double(n), sum_all, outer_all, s.up);
  if (!one) return std::nullopt;
  std::array<Plane, 2> best{*one, *one};
  // The crease's line runs along n_a x n_b; the points are split across it where the two sides'
  // planes fit them best (every split in one pass, by running sums).
  Eigen::Vector3d line = seed_normal[0].cross(seed_normal[1]);
  std::vector<std::size_t> order(n);
  std::vector<double> across(n);
  for (int round = 0; round < kRounds && line.norm() > 1e-9; ++round) {
    const Eigen::Vector3d dir = s.up.cross(line).normalized();
    for (std::size_t i = 0; i < n; ++i) across[i] = dir.dot(points[i]);
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return across[a] < across[b]; });
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    double least = best[0].squares + (best[0].point == best[1].point ? 0 : best[1].squares);
    for (std::size_t k = 0; k + kSidePoints <= n; ++k) {
      const Eigen::Vector3d d = points[order[k]] - origin;
      sum += d, outer += d * d.transpose();
      if (k + 1 < kSidePoints) continue;
      const auto a = plane_of(double(k + 1), sum, outer, s.up);
      const auto b = plane_of(double(n - k - 1), sum_all - sum, outer_all - outer, s.up);
      if (a && b && a->squares + b->squares < least) least = a->squares + b->squares, best = {*a, *b};
    }
    line = best[0].normal.cross(best[1].normal);
  }
  for (int i = 0; i < 2; ++i) {
    if (best[i].normal.dot(s.up) < kLeastUp) return std::nullopt;
    s.normal[i] = best[i].normal;
    s.offset[i] = best[i].normal.dot(best[i].point + origin);
  }
  double misfit[2] = {0, 0};  // as a ridge, as a valley
  for (int shape = 0; shape < 2; ++shape) {
    s.ridge = shape == 0;
    for (const auto& p : points) misfit[shape] = std::max(misfit[shape], std::abs(s.height(p)));
  }
  s.ridge = misfit[0] <= misfit[1];
  s.misfit = std::min(misfit[0], misfit[1]);
  return s;
}

}  // namespace scallop
