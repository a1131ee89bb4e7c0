#include <cstdio>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/geom/point_text.h"
#include "nodes/cloud/trim_steep.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"

namespace scallop::cloud_nodes {

namespace {


}  // namespace

NodeDecl make_trim_steep_node() {
  NodeDecl d;
  d.type = "cloud.trim_steep";
  d.version = 5;  // 5: the points not kept as an output, left_out; 2: the kept cloud's k nearest neighbours as an output; 3: a piece apart is said so (the cached warning); 4: a gentle point joins only gentle neighbours nearer than its first steep one
  d.description =
      "trims a patch's steep rim (points steeper than max_slope, and what that cuts off) so the "
      "rest can be planned and certified; the trimmed band is reported as not machined";
  d.input("cloud", "Cloud", "the points")
      .output("cloud", "Cloud", "the largest connected piece of the points not steeper than max_slope, in their order")
      .output("neighbors", "Neighbors",
              "k nearest neighbours of each kept point among the kept points, nearest first, as "
              "cloud.knn gives them (the trim's own when every point is kept: a graph need not "
              "search them twice)")
      .output("left_out", "Cloud",
              "the points not kept (steep, or cut off by steep ones, or apart), in their order: not "
              "machined, but the ball must keep clear of them (path.gouge_guard's and post.link's left_out)")
      .output("report", "Report",
              "{points, kept, steep (steeper than max_slope), cut_off (gentle points in smaller "
              "pieces), area_mm2, trimmed_area_mm2, trimmed_fraction (of the area), "
              "max_slope_kept_deg, regions: [{points, area_mm2, centroid, min, max, "
              "max_slope_deg}] (the trimmed pieces, largest first, at most 10)}");
  d.options<TrimSteepOptions>()
      .number("max_slope", &TrimSteepOptions::max_slope_deg, 1, 90, "deg",
              "points whose tangent plane is steeper than this to the xy plane are not "
              "machined (90: nothing is trimmed)")
      .integer("k", &TrimSteepOptions::k, 3, 256, "",
               "neighbours of the slope estimate, of the connectivity and of the output 'neighbors'");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    const TrimSteepOptions o = ctx.options<TrimSteepOptions>();
    TrimSteepResult r;
    try {
      r = trim_steep(cloud->points, o);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    const std::size_t trimmed = cloud->size() - r.kept.size();
    nlohmann::json regions = nlohmann::json::array();
    for (const TrimmedRegion& g : r.regions)
      regions.push_back({{"points", g.points}, {"area_mm2", g.area}, {"centroid", json_xyz(g.centroid)},
                         {"min", json_xyz(g.min)}, {"max", json_xyz(g.max)}, {"max_slope_deg", g.max_slope_deg}});
    Report report;
    report.data = {{"points", cloud->size()},
                   {"kept", r.kept.size()},
                   {"steep", r.steep},
                   {"cut_off", r.cut_off},
                   {"max_slope", o.max_slope_deg},
                   {"area_mm2", r.area},
                   {"trimmed_area_mm2", r.trimmed_area},
                   {"trimmed_fraction", r.area > 0 ? r.trimmed_area / r.area : 0.0},
                   {"max_slope_kept_deg", r.max_slope_kept_deg},
                   {"regions", regions}};
    if (r.kept.size() < 10)
      throw NodeError("only " + std::to_string(r.kept.size()) + " of " + std::to_string(cloud->size()) +
                      " points are not steeper than " + short_number(o.max_slope_deg) +
                      " degrees: nothing left to machine from above (raise max_slope)");
    if (trimmed > 0) {
      const TrimmedRegion& g = r.regions.front();
      // With no steep point the pieces left are apart from the patch whatever max_slope is (a
      // clamp, a second object in the scan): raising it would not keep them.
      const std::string what =
          r.steep == 0 ? " apart from the largest connected piece, which is machined"
                       : " steeper than " + short_number(o.max_slope_deg) + " degrees or cut off by them";
      const std::string advice =
          r.steep == 0 ? "; not connected to it through their " + std::to_string(o.k) +
                             " nearest neighbours: give such a piece as a part of its own to machine it"
                       : "; raise max_slope to keep more";
      const std::size_t pieces = r.regions.size();
      ctx.warn("not machined: " + std::to_string(trimmed) + " points (" + short_number(r.trimmed_area) +
               " mm2, " + short_number(100 * r.trimmed_area / r.area) + " % of the area)" + what + ", in " +
               std::to_string(pieces) + (pieces == 10 ? " or more" : "") + (pieces == 1 ? " piece" : " pieces") +
               "; the largest (" + short_number(g.area) + " mm2) from x " + short_number(g.min.x()) + " to " +
               short_number(g.max.x()) + ", y " + short_number(g.min.y()) + " to " + short_number(g.max.y()) + advice);
    }
    PointCloud out, left_out;
    out.points.reserve(r.kept.size());
    left_out.points.reserve(trimmed);
    std::vector<char> kept(cloud->size(), 0);
    for (std::size_t i : r.kept) {
      kept[i] = 1;
      out.points.push_back(cloud->points[i]);
      if (cloud->has_normals()) out.normals.push_back(cloud->normals[i]);
      if (cloud->has_uncertainty()) out.uncertainty.push_back(cloud->uncertainty[i]);
    }
    for (std::size_t i = 0; i < cloud->size(); ++i)
      if (!kept[i]) left_out.points.push_back(cloud->points[i]);
    if (r.neighbors.size() != out.size())
      throw NodeError("only " + std::to_string(out.size()) + " points are kept: the " + std::to_string(o.k) +
                      " nearest neighbours of each need more (raise max_slope or lower k)");
    ctx.set("report", std::move(report));
    ctx.set("cloud", std::move(out));
    ctx.set("left_out", std::move(left_out));
    ctx.set("neighbors", std::move(r.neighbors));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
