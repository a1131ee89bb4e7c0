// A patch's outline in the plane: closed polygons (the outer one and its holes), tested by the
// even-odd rule, so a point is inside when an odd number of them contain it (inside the outer
// loop and outside every hole).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
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
  // How far q lies outside the first loop (the outer one, as the boundary loops come), in xy:
  // 0 inside it; +infinity without loops. Found from the nearest edge (a k-d tree search), not
  // by walking the loop: the guard asks it for every foot beyond the outline. The band beyond it is what path.isoparametric's band
  // passes cut and post.simulate counts (rim_band_width, nodes/path/step_size.h).
  double beyond_outer(const Eigen::Vector2d& q) const;
  // The distance from q to the first loop's edges, inside or out (+infinity without loops).
  double distance_to_outer(const Eigen::Vector2d& q) const;

 private:
  struct Loop {
    std::vector<Eigen::Vector2d> polygon;
    Eigen::AlignedBox2d box;
  };
  struct EdgeIndex;  // the outer loop's edges, sampled, in a k-d tree
  // The distance from q to the outer loop's nearest edge, and (given inside) whether q lies
  // inside the loop, from the side of that edge.
  double nearest_on_outer(const Eigen::Vector2d& q, bool* inside) const;
  std::vector<Loop> loops_;
  std::shared_ptr<const EdgeIndex> outer_edges_;
  double outer_orientation_ = 1;  // +1 counter-clockwise, -1 clockwise
};

}  // namespace scallop
