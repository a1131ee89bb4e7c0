// A patch's outline in the plane: closed polygons (the outer one and its holes), tested by the
// even-odd rule, so a point is inside when an odd number of them contain it (inside the outer
// loop and outside every hole).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace scallop {

// True when q lies inside the closed polygon (even-odd rule; the closing edge is implied).
bool polygon_contains(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& q);

// Twice the signed area of a closed polygon (the shoelace sum; the closing edge is implied):
// positive when it runs counter-clockwise.
double twice_signed_area(const std::vector<Eigen::Vector2d>& polygon);

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
  // How far q lies off the patch in xy: outside the outer loop or inside a hole, the distance to
  // the nearest loop's edges; 0 on the patch; +infinity without loops. Found from the nearest
  // edge (a k-d tree search over every loop's edges), not by walking the loops: the guard asks it
  // for every foot off the patch. The band off the patch is what path.isoparametric's band
  // passes cut, beyond the outer loop and into the holes, and post.simulate counts
  // (rim_band_width, nodes/path/step_size.h): a hole's edge lies beyond the cloud's points
  // around it as the outline does beyond its outermost ones.
  double beyond(const Eigen::Vector2d& q) const;
  // How far q lies from the nearest loop's edges, on either side; +infinity without loops.
  double edge_distance(const Eigen::Vector2d& q) const;

 private:
  struct Loop {
    std::vector<Eigen::Vector2d> polygon;
    Eigen::AlignedBox2d box;
    double orientation = 1;  // +1 counter-clockwise, -1 clockwise
    bool patch_inside = true;  // the patch lies inside it (the outer loop), not outside (a hole)
  };
  struct EdgeIndex;  // every loop's edges, sampled, in a k-d tree
  struct NearestEdge {
    double distance = std::numeric_limits<double>::infinity();
    double t = 0;                         // where along the edge, in [0, 1]
    std::uint32_t loop = 0, edge = 0;     // edge: from corner `edge` to the next
  };
  NearestEdge nearest_edge(const Eigen::Vector2d& q) const;  // loops not empty
  std::vector<Loop> loops_;
  std::shared_ptr<const EdgeIndex> edges_;
};

}  // namespace scallop
