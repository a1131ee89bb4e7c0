#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/boundary_order.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::cloud_nodes {

NodeDecl make_boundary_order_node() {
  NodeDecl d;
  d.type = "cloud.boundary_order";
  d.version = 2;  // 2: a loop that closes by short links is not joined to another loop by a long one (a hole near the outline), and a stretch of loop hanging off the tree goes into the tour whole (stop 91)
  d.description = "order boundary points into closed loops, outer loop first (MST longest path + 2-opt)";
  d.input("cloud", "Cloud", "the points (normals, when present, orient the loops)")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point")
      .input("loops", "Loops", "boundary flags from cloud.boundary")
      .output("loops", "Loops", "the same flags with loops: outer first (counter-clockwise), then holes")
      .param_int("min_loop_points", 8, 3, 1000000, "", "pieces of boundary with fewer points are dropped as noise");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    auto in = ctx.input<BoundaryLoops>("loops");
    BoundaryLoops out;
    out.is_boundary = in->is_boundary;
    try {
      out.loops = order_boundary_loops(cloud->points, cloud->has_normals() ? cloud->normals : std::vector<Eigen::Vector3d>{},
                                       *nbrs, in->is_boundary, static_cast<int>(ctx.integer("min_loop_points")));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    ctx.set("loops", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
