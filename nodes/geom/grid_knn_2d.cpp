#include "nodes/geom/grid_knn_2d.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace scallop {

namespace {
constexpr double kPointsPerCell = 2;
}

GridKnn2d::GridKnn2d(const std::vector<Eigen::Vector2d>& P) { build(P); }
GridKnn2d::GridKnn2d(const std::vector<Eigen::Vector3d>& P) { build(P); }

template <class Point>
void GridKnn2d::build(const std::vector<Point>& P) {
  if (P.empty()) throw std::invalid_argument("no points to search");
  Eigen::Vector2d lo = P[0].template head<2>(), hi = lo;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!P[i].template head<2>().allFinite())
      throw std::invalid_argument("point " + std::to_string(i) + " has a NaN or infinite coordinate");
    lo = lo.cwiseMin(P[i].template head<2>());
    hi = hi.cwiseMax(P[i].template head<2>());
  }
  const std::size_t n = P.size();
  const double w = hi.x() - lo.x(), h = hi.y() - lo.y(), span = std::max(w, h);
  // About kPointsPerCell points a cell where they spread over the box; no more than 4n cells where
  // they do not (all on a line).
  cell_ = std::sqrt(kPointsPerCell * std::max(w, 1e-9 * span) * std::max(h, 1e-9 * span) / double(n));
  if (!(cell_ > 1e-12 * span) || !std::isfinite(cell_)) cell_ = span > 0 ? span : 1.0;  // one place
  auto cells_along = [&](double extent) { return static_cast<long>(std::floor(extent / cell_)) + 1; };
  while (double(cells_along(w)) * double(cells_along(h)) > 4.0 * double(n) + 16) cell_ *= 1.5;
  x0_ = lo.x(), y0_ = lo.y();
  slack_ = 1e-13 * (lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).maxCoeff() + cell_);
  nx_ = static_cast<int>(cells_along(w)), ny_ = static_cast<int>(cells_along(h));
  auto cell_of = [&](const Point& p) {
    return std::size_t(column_of(p.y(), y0_, ny_)) * std::size_t(nx_) + std::size_t(column_of(p.x(), x0_, nx_));
  };
  // Counting sort by cell, each cell's points in index order.
  start_.assign(std::size_t(nx_) * std::size_t(ny_) + 1, 0);
  std::vector<std::uint32_t> cell(n);
  for (std::size_t i = 0; i < n; ++i) ++start_[(cell[i] = std::uint32_t(cell_of(P[i]))) + 1];
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
  point_.resize(n);
  index_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t at = next[cell[i]]++;
    point_[at] = P[i].template head<2>();
    index_[at] = std::uint32_t(i);
  }
}

int GridKnn2d::column_of(double x, double origin, int count) const {
  // clamped before the conversion: a query far outside would overflow an int
  return static_cast<int>(std::clamp(std::floor((x - origin) / cell_), 0.0, double(count - 1)));
}

int GridKnn2d::query(const Eigen::Vector2d& q, int k, std::uint32_t* idx, double* sq) const {
  if (k < 1) throw std::invalid_argument("k must be at least 1");
  const int want = static_cast<int>(std::min<std::size_t>(std::size_t(k), index_.size()));
  int count = 0;
  double worst = std::numeric_limits<double>::infinity();  // the k-th distance once k are kept
  // Keeps the `want` nearest seen, sorted by distance, then index.
  auto offer = [&](double d, std::uint32_t i) {
    if (d > worst || (d == worst && count == want && i > idx[count - 1])) return;
    int j = count < want ? count++ : count - 1;
    for (; j > 0 && (sq[j - 1] > d || (sq[j - 1] == d && idx[j - 1] > i)); --j) sq[j] = sq[j - 1], idx[j] = idx[j - 1];
    sq[j] = d, idx[j] = i;
    if (count == want) worst = sq[count - 1];
  };
  auto visit = [&](int cx, int cy) {
    const std::size_t c = std::size_t(cy) * std::size_t(nx_) + std::size_t(cx);
    for (std::uint32_t e = start_[c], end = start_[c + 1]; e < end; ++e) {
      const double d = (point_[e] - q).squaredNorm();
      if (d <= worst) offer(d, index_[e]);
    }
  };
  const int cx = column_of(q.x(), x0_, nx_), cy = column_of(q.y(), y0_, ny_);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int ring = 0;; ++ring) {
    const int xlo = cx - ring, xhi = cx + ring, ylo = cy - ring, yhi = cy + ring;
    for (int y = std::max(ylo, 0); y <= std::min(yhi, ny_ - 1); ++y) {
      if (y == ylo || y == yhi) {
        for (int x = std::max(xlo, 0); x <= std::min(xhi, nx_ - 1); ++x) visit(x, y);
      } else {
        if (xlo >= 0) visit(xlo, y);
        if (xhi < nx_) visit(xhi, y);
      }
    }
    // How near q a cell outside this block can be, over the sides where the grid goes on.
    double bound = kInf;
    if (xlo > 0) bound = std::min(bound, q.x() - (x0_ + xlo * cell_));
    if (xhi < nx_ - 1) bound = std::min(bound, x0_ + (xhi + 1) * cell_ - q.x());
    if (ylo > 0) bound = std::min(bound, q.y() - (y0_ + ylo * cell_));
    if (yhi < ny_ - 1) bound = std::min(bound, y0_ + (yhi + 1) * cell_ - q.y());
    if (bound == kInf) break;  // every cell visited
    bound -= slack_;  // a point on a cell's edge may have been rounded into the next cell
    if (count == want && bound > 0 && bound * bound > sq[count - 1]) break;
  }
  return count;
}

void GridKnn2d::query(const Eigen::Vector2d& q, int k, std::vector<std::uint32_t>& idx,
                      std::vector<double>& sq) const {
  if (k < 1) throw std::invalid_argument("k must be at least 1");
  const std::size_t want = std::min<std::size_t>(std::size_t(k), index_.size());
  idx.resize(want);
  sq.resize(want);
  query(q, k, idx.data(), sq.data());
}

}  // namespace scallop
