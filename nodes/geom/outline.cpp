#include "nodes/geom/outline.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "nodes/geom/kd_tree.h"

namespace scallop {

bool polygon_contains(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& q) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > q.y()) != (poly[j].y() > q.y()) &&
        q.x() < (poly[j].x() - poly[i].x()) * (q.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) + poly[i].x())
      in = !in;
  return in;
}

struct Outline::EdgeIndex {
  std::vector<Eigen::Vector2d> at;  // points along the edges, at most a median edge apart
  std::vector<std::uint32_t> edge;  // the edge each lies on (from polygon[k] to polygon[k + 1])
  PointsAdaptor<Eigen::Vector2d> adaptor{at};
  std::unique_ptr<KdTree<Eigen::Vector2d, 2>> tree;
};

Outline::Outline(std::vector<std::vector<Eigen::Vector2d>> loops) {
  for (auto& polygon : loops) {
    if (polygon.size() < 3) continue;
    Eigen::AlignedBox2d box;
    for (const auto& q : polygon) box.extend(q);
    loops_.push_back({std::move(polygon), box});
  }
  if (loops_.empty()) return;
  const auto& P = loops_[0].polygon;
  const std::size_t n = P.size();
  std::vector<double> length(n);
  for (std::size_t k = 0; k < n; ++k) length[k] = (P[(k + 1) % n] - P[k]).norm();
  std::vector<double> sorted = length;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
  const double step = std::max(sorted[n / 2], 1e-12);
  auto index = std::make_shared<EdgeIndex>();
  for (std::size_t k = 0; k < n; ++k) {
    const int m = std::max(1, static_cast<int>(std::ceil(length[k] / step)));
    for (int t = 0; t < m; ++t) {
      index->at.push_back(P[k] + (P[(k + 1) % n] - P[k]) * (double(t) / m));
      index->edge.push_back(static_cast<std::uint32_t>(k));
    }
  }
  index->tree = std::make_unique<KdTree<Eigen::Vector2d, 2>>(2, index->adaptor,
                                                              nanoflann::KDTreeSingleIndexAdaptorParams(16));
  index->tree->buildIndex();
  outer_edges_ = std::move(index);
  double area2 = 0;
  for (std::size_t k = 0; k < n; ++k) area2 += P[k].x() * P[(k + 1) % n].y() - P[(k + 1) % n].x() * P[k].y();
  outer_orientation_ = area2 >= 0 ? 1.0 : -1.0;
}

double Outline::beyond_outer(const Eigen::Vector2d& q) const {
  if (loops_.empty()) return std::numeric_limits<double>::infinity();
  bool inside = false;
  const double d = nearest_on_outer(q, &inside);
  return inside ? 0.0 : d;
}

double Outline::distance_to_outer(const Eigen::Vector2d& q) const { return nearest_on_outer(q, nullptr); }

double Outline::nearest_on_outer(const Eigen::Vector2d& q, bool* inside) const {
  if (loops_.empty()) return std::numeric_limits<double>::infinity();
  const auto& P = loops_[0].polygon;
  const std::size_t n = P.size();
  // The nearest edge is among those of the 8 nearest edge points (they are at most a median
  // edge apart along every edge).
  constexpr std::size_t kNear = 8;
  std::uint32_t near[kNear];
  double d2[kNear];
  const double at[2] = {q.x(), q.y()};
  const std::size_t got = outer_edges_->tree->knnSearch(at, kNear, near, d2);
  double best = std::numeric_limits<double>::infinity(), best_t = 0;
  std::uint32_t best_k = 0;
  for (std::size_t i = 0; i < got; ++i) {
    const std::uint32_t k = outer_edges_->edge[near[i]];
    const Eigen::Vector2d a = P[k], ab = P[(k + 1) % n] - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    const double d = (a + t * ab - q).norm();
    if (d < best) best = d, best_t = t, best_k = k;
  }
  if (inside) {
    // Which side of the nearest edge q lies on (the inside is to the left of a counter-clockwise
    // loop); nearest a corner, of both its edges: inside a convex corner is left of both, inside
    // a reflex one left of either. Exact for a simple polygon, without walking its edges.
    auto left_of = [&](std::size_t k) {
      const Eigen::Vector2d a = P[k], ab = P[(k + 1) % n] - a, aq = q - a;
      return outer_orientation_ * (ab.x() * aq.y() - ab.y() * aq.x()) > 0;
    };
    if (best_t > 0 && best_t < 1) {
      *inside = left_of(best_k);
    } else {
      const std::size_t v = best_t >= 1 ? (best_k + 1) % n : best_k, before = (v + n - 1) % n;
      const Eigen::Vector2d e0 = P[v] - P[before], e1 = P[(v + 1) % n] - P[v];
      const bool convex = outer_orientation_ * (e0.x() * e1.y() - e0.y() * e1.x()) >= 0;
      *inside = convex ? left_of(before) && left_of(v) : left_of(before) || left_of(v);
    }
  }
  return best;
}

bool Outline::contains(const Eigen::Vector2d& q) const {
  bool in = false;
  for (const Loop& l : loops_)
    if (l.box.contains(q) && polygon_contains(l.polygon, q)) in = !in;
  return in;
}

bool Outline::any_contains(const Eigen::Vector2d& q) const {
  for (const Loop& l : loops_)
    if (l.box.contains(q) && polygon_contains(l.polygon, q)) return true;
  return false;
}

}  // namespace scallop
