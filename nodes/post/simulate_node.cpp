#include <stdexcept>

#include "engine/node.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_simulate_node() {
  NodeDecl d;
  d.type = "post.simulate";
  d.version = 8;  // 3: scallop and gouge are bounds that include the cloud's uncertainty; 7: and the height field's misfit; 8: the height field solved by a fixed-size Cholesky (the same to rounding)
                  // 4: the uncertainty grows at gaps beyond the cloud's edge
                  // 5: pass asks the whole patch, rim included, not the interior only
                  // 6: outputs the simulation (post.render draws it), no heat map of its own
  d.description = "cutting simulation over the cloud's surface: scallop, gouge and uncut area (the certificate)";
  d.input("path", "Toolpath", "planned passes (give this or 'linked')", false)
      .input("linked", "LinkedPath", "linked machine moves (give this or 'path')", false)
      .input("cloud", "Cloud", "the surface, seen from +z; with per-point uncertainty, scallop and gouge are bounds for the real surface (the estimate's plus the uncertainty)")
      .input("loops", "Loops", "the patch's boundary loops (outer first, then holes; indices into 'cloud'): "
             "the patch is what lies inside them in xy, and the margin is measured from them; "
             "absent: the outline is guessed from the cloud", false)
      .output("report", "Report", "scallop/gouge/uncut statistics (whole patch, rim included, and interior), pass (the whole patch within the limits) and fail reasons, the 10 worst places")
      .output("simulation", "Simulation",
              "what the path left at every surface sample and the limits judged against, for "
              "pictures (post.render, view 'scallop')")
      .param_float("scallop", 0, 0, 100, "mm", "scallop limit h; 0: the path's own")
      .param_float("chord", -1, -1, 100, "mm", "chord tolerance e (gouges up to max(e, 0.001) pass); -1: the path's own");
  // scallop and chord stand for the path's own limits at 0 and -1: resolved in run, not bound
  d.options<SimulateOptions>()
      .number("spacing", &SimulateOptions::spacing, 0, 100, "mm", "grid spacing; 0: sqrt(8 r h)/12")
      .number("margin", &SimulateOptions::margin, 0, 1000, "mm",
              "interior = farther than this from the outline; 0: sqrt(8 r h)")
      .integer("max_samples", &SimulateOptions::max_samples, 1000, 100000000, "",
               "the spacing is raised to stay below this many samples");
  d.run = [](NodeContext& ctx) {
    if (ctx.has_input("path") == ctx.has_input("linked"))
      throw NodeError("give exactly one of the inputs 'path' and 'linked'");
    auto cloud = ctx.input<PointCloud>("cloud");
    std::vector<CentreSegment> feed;
    double rapid = 0, r, h, e;
    if (ctx.has_input("path")) {
      auto p = ctx.input<Toolpath>("path");
      feed = feed_centres(*p);
      r = p->tool_radius, h = p->scallop_height, e = p->chord_error;
    } else {
      auto p = ctx.input<LinkedPath>("linked");
      feed = feed_centres(*p, rapid);
      r = p->tool_radius, h = p->scallop_height, e = p->chord_error;
    }
    SimulateOptions o = ctx.options<SimulateOptions>();
    o.tool_radius = r;
    o.scallop = ctx.number("scallop") > 0 ? ctx.number("scallop") : h;
    o.chord = ctx.number("chord") >= 0 ? ctx.number("chord") : e;
    try {
      if (ctx.has_input("loops")) o.loops = loop_polygons_xy(*ctx.input<BoundaryLoops>("loops"), cloud->points);
      HeightFieldModel surf(cloud->points, 20, cloud->has_uncertainty() ? &cloud->uncertainty : nullptr);
      Simulation sim = simulate_cut(surf, feed, rapid, o, [&](double f) { ctx.progress(f, "simulating"); });
      Report rep;
      rep.data = sim.report;
      ctx.set("report", std::move(rep));
      ctx.set("simulation", std::move(sim));
    } catch (const std::invalid_argument& ex) {
      throw NodeError(ex.what());
    }
  };
  return d;
}
}  // namespace scallop::post_nodes
