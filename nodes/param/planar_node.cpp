#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/planar_map.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::param_nodes {

NodeDecl make_planar_node() {
  NodeDecl d;
  d.type = "param.planar";
  d.version = 1;
  d.description =
      "parameterise a height field by its own xy, turned to the passes' direction: a raster that cannot fold "
      "over, for outlines a harmonic map cannot follow";
  d.input("cloud", "Cloud", "the points, a height field seen from +z")
      .input("loops", "Loops", "ordered boundary loops; loops[0] is the outline (the rest, holes, are the planner's)")
      .output("map", "UVMap", "domain 'planar': uv = the points' xy turned, over [0,width] x [0,height]; "
                              "off the outline is off the patch")
      .param_float("angle", -1, -1, 180, "deg",
                   "the passes' direction in xy from +x; -1: across the patch's longer principal extent (its short "
                   "way, as the harmonic zig-zag runs)");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto loops = ctx.input<BoundaryLoops>("loops");
    if (loops->loops.empty()) throw NodeError("no boundary loop: run cloud.boundary_order first");
    try {
      ctx.set("map", planar_map(cloud->points, loops->loops[0], ctx.number("angle")));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::param_nodes
