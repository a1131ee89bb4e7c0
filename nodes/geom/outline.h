// A patch's outline in the plane: closed polygons (the outer one and its holes), tested by the
// even-odd rule, so a point is inside when an odd number of them contain it (inside the outer
// loop and outside every hole).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace scallop {

// True when q lies inside the closed polygon (even-odd rule; the closing edge is implied).
bool polygon_contains(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& q);

class Outline {
 public:
  Outline() = default;
  // loops  closed polygons (mm or parameter units), the outer one and its holes, in any order;
  //        loops with fewer than 3 corners are ignored.
  explicit Outline(std::vector<std::vector<Eigen::Vector2d>> loops);
  bool empty() const { return loops_.empty(); }
  // inside an odd number of the loops
  bool contains(const Eigen::Vector2d& q) const;
  // inside any one of the loops (their union: e.g. a set of holes)
  bool any_contains(const Eigen::Vector2d& q) const;

 private:
  struct Loop {
    std::vector<Eigen::Vector2d> polygon;
    Eigen::AlignedBox2d box;
  };
  std::vector<Loop> loops_;
};

}  // namespace scallop
