#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/cloud_height_field.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_simulate_node() {
  NodeDecl d;
  d.type = "post.simulate";
  d.version = 15;  // 15: the rim band reaches into the holes too (stop 90); 14: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 13: the height field's quartic where its quadratic misfits (HeightFieldModel, kQuarticFrom); 12: rim_band, the band beyond the outer loop counted too when asked (samples_beyond_outline);  11: a gouge bound below the uncertainty says the ball stays clear of the surface by less than it; 10: a failing bound says how much of it is the surface's uncertainty, and the worst places carry it; 9: the rapids checked against the cloud (rapid_min_clearance, rapids_through_part); 3: scallop and gouge are bounds that include the cloud's uncertainty; 7: and the height field's misfit; 8: the height field solved by a fixed-size Cholesky (the same to rounding)
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
      .input("samples", "SurfaceSamples",
             "the surface sampled before (post.surface_samples, given the same cloud, loops, tool radius, scallop "
             "limit and grid parameters: the same simulation); absent: sampled here",
             false)
      .output("report", "Report", "scallop/gouge/uncut statistics (whole patch, rim included, and interior), with a linked path the rapids' least clearance from the cloud (rapid_min_clearance, rapids_through_part), pass (the whole patch within the limits, no rapid through it) and fail reasons, the 10 worst places")
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
      .number("rim_band", &SimulateOptions::rim_band, -1, 100, "mm",
              "with loops, the band beyond the outer loop and into the holes also counted (its width along the surface; "
              "path.isoparametric's band passes cut three spacings): -1: the cloud's support, one "
              "spacing past its outermost points; 0: none, the outline only")
      .integer("max_samples", &SimulateOptions::max_samples, 1000, 100000000, "",
               "the spacing is raised to stay below this many samples");
  d.run = [](NodeContext& ctx) {
    if (ctx.has_input("path") == ctx.has_input("linked"))
      throw NodeError("give exactly one of the inputs 'path' and 'linked'");
    auto cloud = ctx.input<PointCloud>("cloud");
    std::vector<CentreSegment> feed, rapids;
    double rapid = 0, r, h, e;
    if (ctx.has_input("path")) {
      auto p = ctx.input<Toolpath>("path");
      feed = feed_centres(*p);
      r = p->tool_radius, h = p->scallop_height, e = p->chord_error;
    } else {
      auto p = ctx.input<LinkedPath>("linked");
      feed = feed_centres(*p, rapid, &rapids);
      r = p->tool_radius, h = p->scallop_height, e = p->chord_error;
    }
    SimulateOptions o = ctx.options<SimulateOptions>();
    o.tool_radius = r;
    o.scallop = ctx.number("scallop") > 0 ? ctx.number("scallop") : h;
    o.chord = ctx.number("chord") >= 0 ? ctx.number("chord") : e;
    try {
      if (ctx.has_input("loops")) o.loops = loop_polygons_xy(*ctx.input<BoundaryLoops>("loops"), cloud->points);
      // The rapids come down to a ball of r + lead_height above the part (post.link): checked,
      // as verify.py checks them, against the cloud's points raised by their uncertainty, beside
      // the simulation (their k-d tree over a million points takes 0.7 s on one thread).
      const double tol = std::max(o.chord, 1e-3);
      Simulation sim;
      RapidClearance rc;
      tbb::parallel_invoke(
          [&] {
            const auto progress = [&](double f) { ctx.progress(f, "simulating"); };
            sim = ctx.has_input("samples")
                      ? simulate_cut(*cloud_height_field(*cloud), *ctx.input<SurfaceSamples>("samples"), feed, rapid, o,
                                     progress)
                      : simulate_cut(*cloud_height_field(*cloud), feed, rapid, o, progress);
          },
          [&] {
            if (ctx.has_input("linked"))
              rc = rapid_clearance(cloud->points, cloud->has_uncertainty() ? &cloud->uncertainty : nullptr,
                                   cloud_height_field(*cloud)->tree3d(), rapids, r, tol);
          });
      if (ctx.has_input("linked")) {
        nlohmann::json& j = sim.report;
        j["rapid_min_clearance"] = std::isfinite(rc.least) ? nlohmann::json(rc.least) : nlohmann::json();
        j["rapids_through_part"] = rc.through;
        if (rc.through > 0) {
          char buf[200];
          std::snprintf(buf, sizeof buf, "%zu rapids pass through the surface (least clearance %.4g mm at (%.3f, %.3f, %.3f))",
                        rc.through, rc.least, rc.at.x(), rc.at.y(), rc.at.z());
          j["fail_reasons"].push_back(buf);
          j["pass"] = false;
        }
      }
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
