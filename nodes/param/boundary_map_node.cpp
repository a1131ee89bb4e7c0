#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/boundary_map.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::param_nodes {

NodeDecl make_boundary_map_node() {
  NodeDecl d;
  d.type = "param.boundary_map";
  d.version = 3;  // 3: the rectangle's longer sides along u (zig-zag passes the short way)
  d.description = "map the outer boundary loop by chord length to a circle or a rectangle";
  d.input("cloud", "Cloud", "the points")
      .input("loops", "Loops", "ordered boundary loops; loops[0] is mapped")
      .output("map", "UVMap", "partial map: domain, size, outer_loop, boundary_uv, corners (uv empty)")
      .param_choice("domain", "rectangle", {"disk", "rectangle"},
                    "disk: circle of radius L/2pi (contour-parallel); rectangle: direction-parallel, its longer pair of sides along u, so that zig-zag passes (iso-u lines) run the patch's short way")
      .param_string("corners", "",
                    "rectangle corners as 4 outer-loop positions \"i,j,k,l\"; empty: the 4 sharpest turns");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto loops = ctx.input<BoundaryLoops>("loops");
    if (loops->loops.empty()) throw NodeError("no boundary loop: run cloud.boundary_order first");
    try {
      const auto& outer = loops->loops[0];
      ctx.set("map", map_boundary(cloud->points, outer, parse_boundary_domain(ctx.text("domain")),
                                  parse_corners(ctx.text("corners"), outer.size())));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::param_nodes
