#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/check.h"
#include "nodes/param/untangle.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"

namespace scallop::param_nodes {

NodeDecl make_map_check_node() {
  NodeDecl d;
  d.type = "param.check";
  d.version = 4;  // 4: fold-overs allowed are said in a warning; 3: the untangling keeps its best round, never a map worse than it was given (stop 91); 2: a few fold-overs are untangled locally
  d.description =
      "diagnostics of a (u,v) map: angle distortion and fold-overs; a few fold-overs are "
      "untangled locally, more are an error unless allowed";
  d.input("map", "UVMap", "the harmonic map")
      .input("cloud", "Cloud", "the points, with normals")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point")
      .output("report", "Report", "conformality statistics (sigma1/sigma2) and fold-over count")
      .output("map", "UVMap",
              "the input map once checked (with the untangled points moved, if any)")
      .param_int("untangle_rounds", 10, 0, 100, "",
                 "where at most max(20, 0.5 %) of the points fold, move them and a growing ring "
                 "of neighbours to their neighbours' mean (u,v) (outer-loop points slide along "
                 "the domain's edge, corners stay), for up to this many rounds; 0: never")
      .param_bool("allow_foldovers", false, "report fold-overs instead of failing");
  // Cached: at a million points the check takes 1.5 s and needs the neighbour lists (1.4 s to
  // load), where its map loads in 0.1 s (bench/scale_bench.sh at 1M: warm run 6.7 -> 3.4 s).
  d.run = [](NodeContext& ctx) {
    auto map = ctx.input<UVMap>("map");
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    if (!cloud->has_normals()) throw NodeError("param.check needs normals: run cloud.normals first");
    MapCheck c;
    UntangleResult u;
    try {
      const std::size_t max_folded = std::max<std::size_t>(20, cloud->size() / 200);
      u = untangle_map(cloud->points, cloud->normals, *nbrs, map->uv, map->outer_loop, map->corners,
                       domain_edge(*map), static_cast<int>(ctx.integer("untangle_rounds")), max_folded);
      c = check_map(cloud->points, cloud->normals, *nbrs, u.uv);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    if (c.foldovers > 0 && !ctx.flag("allow_foldovers")) throw NodeError(foldover_message(c, cloud->points));
    if (c.foldovers > 0) {  // allowed: said on the terminal, not only in the report
      const auto& p = cloud->points[std::max<long long>(c.first_foldover, 0)];
      char where[96];
      std::snprintf(where, sizeof where, "%.3f, %.3f, %.3f", p.x(), p.y(), p.z());
      ctx.warn(map->domain == "planar"
                   ? "the cloud overhangs at " + std::to_string(c.foldovers) + " points (first near " + where +
                         "): not a height field seen from +z there (noise on a steep flank?); the raster's passes "
                         "cross them in xy and the guard keeps the ball off them"
                   : "the (u,v) map folds over at " + std::to_string(c.foldovers) + " points (first near " + where +
                         "), planned anyway (allow_foldovers): the passes there may cross; the certificate says "
                         "whether they hold");
    }
    Report r;
    r.data = std::move(c.report);
    r.data["domain"] = map->domain;
    r.data["residual"] = map->residual;
    if (map->domain == "disk") r.data["radius"] = map->radius;
    if (map->domain == "rectangle") r.data["size"] = {map->width, map->height};
    r.data["untangled"] = {{"folded_before", u.folded_before},
                           {"moved_points", u.moved},
                           {"rounds", u.rounds}};
    ctx.set("report", std::move(r));
    if (u.moved == 0) {
      ctx.set_output("map", map);
      return;
    }
    ctx.progress(1.0, "untangled " + std::to_string(u.folded_before) + " fold-overs (" +
                          std::to_string(u.moved) + " points moved)");
    UVMap out = *map;
    out.uv = std::move(u.uv);
    ctx.set("map", std::move(out));
  };
  return d;
}

}  // namespace scallop::param_nodes
