#include <numbers>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/boundary.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::cloud_nodes {

NodeDecl make_boundary_node() {
  NodeDecl d;
  d.type = "cloud.boundary";
  d.version = 1;
  d.description = "boundary points of an open patch: largest angular gap between tangent-projected neighbours";
  d.input("cloud", "Cloud", "the points, with normals")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point (k >= 3)")
      .output("loops", "Loops", "is_boundary set; loops empty (cloud.boundary_order fills them)")
      .param_float("angle", 90.0, 30.0, 300.0, "deg",
                   "a point is on the boundary when its neighbours leave an angular gap larger than this")
      .param_bool("clean", true, "drop boundary points that have fewer than 2 boundary neighbours (noise)");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    if (!cloud->has_normals()) throw NodeError("cloud.boundary needs normals: run cloud.normals first");
    BoundaryLoops out;
    try {
      out.is_boundary = detect_boundary(cloud->points, cloud->normals, *nbrs,
                                        ctx.number("angle") * std::numbers::pi / 180, ctx.flag("clean"),
                                        [&ctx](double f) { ctx.progress(f); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    ctx.set("loops", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
