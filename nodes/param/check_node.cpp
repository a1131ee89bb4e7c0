#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/check.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"

namespace scallop {

NodeDecl make_map_check_node() {
  NodeDecl d;
  d.type = "param.check";
  d.version = 1;
  d.description = "diagnostics of a (u,v) map: angle distortion and fold-overs (an error unless allowed)";
  d.input("map", "UVMap", "the harmonic map")
      .input("cloud", "Cloud", "the points, with normals")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point")
      .output("report", "Report", "conformality statistics (sigma1/sigma2) and fold-over count")
      .output("map", "UVMap", "the input map, passed through once checked")
      .param_bool("allow_foldovers", false, "report fold-overs instead of failing");
  d.cache_on_disk = false;
  d.run = [](NodeContext& ctx) {
    auto map = ctx.input<UVMap>("map");
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    if (!cloud->has_normals()) throw NodeError("param.check needs normals: run cloud.normals first");
    MapCheck c;
    try {
      c = check_map(cloud->points, cloud->normals, *nbrs, map->uv);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    if (c.foldovers > 0 && !ctx.flag("allow_foldovers")) throw NodeError(foldover_message(c, cloud->points));
    Report r;
    r.data = std::move(c.report);
    r.data["domain"] = map->domain;
    r.data["residual"] = map->residual;
    if (map->domain == "disk") r.data["radius"] = map->radius;
    if (map->domain == "rectangle") r.data["size"] = {map->width, map->height};
    ctx.set("report", std::move(r));
    ctx.set_output("map", map);
  };
  return d;
}

}  // namespace scallop
