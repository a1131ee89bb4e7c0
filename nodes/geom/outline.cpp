#include "nodes/geom/outline.h"

namespace scallop {

bool polygon_contains(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& q) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > q.y()) != (poly[j].y() > q.y()) &&
        q.x() < (poly[j].x() - poly[i].x()) * (q.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) + poly[i].x())
      in = !in;
  return in;
}

Outline::Outline(std::vector<std::vector<Eigen::Vector2d>> loops) {
  for (auto& polygon : loops) {
    if (polygon.size() < 3) continue;
    Eigen::AlignedBox2d box;
    for (const auto& q : polygon) box.extend(q);
    loops_.push_back({std::move(polygon), box});
  }
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
