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

double twice_signed_area(const std::vector<Eigen::Vector2d>& polygon) {
  double area2 = 0;
  for (std::size_t k = 0, n = polygon.size(); k < n; ++k)
    area2 += polygon[k].x() * polygon[(k + 1) % n].y() - polygon[(k + 1) % n].x() * polygon[k].y();
  return area2;
}

struct Outline::EdgeIndex {
  std::vector<Eigen::Vector2d> at;  // points along the edges, at most a median edge apart
  std::vector<std::uint32_t> loop, edge;  // the loop and edge each lies on (polygon[k] to polygon[k + 1])
  PointsAdaptor<Eigen::Vector2d> adaptor{at};
  std::unique_ptr<KdTree<Eigen::Vector2d, 2>> tree;
};

Outline::Outline(std::vector<std::vector<Eigen::Vector2d>> loops) {
  for (auto& polygon : loops) {
    if (polygon.size() < 3) continue;
    Eigen::AlignedBox2d box;
    for (const auto& q : polygon) box.extend(q);
    const double orientation = twice_signed_area(polygon) >= 0 ? 1.0 : -1.0;
    loops_.push_back({std::move(polygon), box, orientation, true});
  }
  if (loops_.empty()) return;
  // The patch lies inside a loop that an even number of the others contain (even-odd rule).
  for (Loop& l : loops_) {
    int around = 0;
    for (const Loop& other : loops_)
      if (&other != &l && other.box.contains(l.polygon[0]) && polygon_contains(other.polygon, l.polygon[0])) ++around;
    l.patch_inside = around % 2 == 0;
  }
  std::vector<double> length;
  for (const Loop& l : loops_)
    for (std::size_t k = 0, n = l.polygon.size(); k < n; ++k) length.push_back((l.polygon[(k + 1) % n] - l.polygon[k]).norm());
  std::vector<double> sorted = length;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double step = std::max(sorted[sorted.size() / 2], 1e-12);
  auto index = std::make_shared<EdgeIndex>();
  std::size_t e = 0;
  for (std::size_t l = 0; l < loops_.size(); ++l) {
    const auto& P = loops_[l].polygon;
    for (std::size_t k = 0, n = P.size(); k < n; ++k, ++e) {
      const int m = std::max(1, static_cast<int>(std::ceil(length[e] / step)));
      for (int t = 0; t < m; ++t) {
        index->at.push_back(P[k] + (P[(k + 1) % n] - P[k]) * (double(t) / m));
        index->loop.push_back(static_cast<std::uint32_t>(l));
        index->edge.push_back(static_cast<std::uint32_t>(k));
      }
    }
  }
  index->tree = std::make_unique<KdTree<Eigen::Vector2d, 2>>(2, index->adaptor,
                                                              nanoflann::KDTreeSingleIndexAdaptorParams(16));
  index->tree->buildIndex();
  edges_ = std::move(index);
}

Outline::NearestEdge Outline::nearest_edge(const Eigen::Vector2d& q) const {
  // The nearest edge is among those of the 8 nearest edge points (they are at most a median
  // edge apart along every edge).
  constexpr std::size_t kNear = 8;
  std::uint32_t near[kNear];
  double d2[kNear];
  const double at[2] = {q.x(), q.y()};
  const std::size_t got = edges_->tree->knnSearch(at, kNear, near, d2);
  NearestEdge best;
  for (std::size_t i = 0; i < got; ++i) {
    const std::uint32_t l = edges_->loop[near[i]], k = edges_->edge[near[i]];
    const auto& P = loops_[l].polygon;
    const Eigen::Vector2d a = P[k], ab = P[(k + 1) % P.size()] - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    const double d = (a + t * ab - q).norm();
    if (d < best.distance) best = {d, t, l, k};
  }
  return best;
}

double Outline::edge_distance(const Eigen::Vector2d& q) const {
  return loops_.empty() ? std::numeric_limits<double>::infinity() : nearest_edge(q).distance;
}

double Outline::beyond(const Eigen::Vector2d& q) const {
  if (loops_.empty()) return std::numeric_limits<double>::infinity();
  const NearestEdge nearest = nearest_edge(q);
  const double best = nearest.distance, best_t = nearest.t;
  const std::uint32_t best_l = nearest.loop, best_k = nearest.edge;
  // Which side of the nearest edge q lies on (the inside is to the left of a counter-clockwise
  // loop); nearest a corner, of both its edges: inside a convex corner is left of both, inside
  // a reflex one left of either. Exact for simple polygons that do not cross, without walking
  // their edges: no other edge comes between q and its nearest.
  const Loop& L = loops_[best_l];
  const auto& P = L.polygon;
  const std::size_t n = P.size();
  auto left_of = [&](std::size_t k) {
    const Eigen::Vector2d a = P[k], ab = P[(k + 1) % n] - a, aq = q - a;
    return L.orientation * (ab.x() * aq.y() - ab.y() * aq.x()) > 0;
  };
  bool inside_loop;
  if (best_t > 0 && best_t < 1) {
    inside_loop = left_of(best_k);
  } else {
    const std::size_t v = best_t >= 1 ? (best_k + 1) % n : best_k, before = (v + n - 1) % n;
    const Eigen::Vector2d e0 = P[v] - P[before], e1 = P[(v + 1) % n] - P[v];
    const bool convex = L.orientation * (e0.x() * e1.y() - e0.y() * e1.x()) >= 0;
    inside_loop = convex ? left_of(before) && left_of(v) : left_of(before) || left_of(v);
  }
  return inside_loop == L.patch_inside ? 0.0 : best;
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
