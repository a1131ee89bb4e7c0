#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/cloud_height_field.h"
#include "nodes/geom/obstacle_points.h"
#include "nodes/geom/point_text.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_simulate_node() {
  NodeDecl d;
  d.type = "post.simulate";
  d.version = 18;  // 18: the refinement also seeds from every cell's highest (refinement_seeds.h), and its samples stay inside the loops; 17: of left_out only the points apart from the patch and above it (obstacle_points); 16: optional left_out: samples no ball reaches beside it reported (beside_left_out), not counted; moves cutting into it fail (stop 92); 15: the rim band reaches into the holes too (stop 90); 14: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 13: the height field's quartic where its quadratic misfits (HeightFieldModel, kQuarticFrom); 12: rim_band, the band beyond the outer loop counted too when asked (samples_beyond_outline);  11: a gouge bound below the uncertainty says the ball stays clear of the surface by less than it; 10: a failing bound says how much of it is the surface's uncertainty, and the worst places carry it; 9: the rapids checked against the cloud (rapid_min_clearance, rapids_through_part); 3: scallop and gouge are bounds that include the cloud's uncertainty; 7: and the height field's misfit; 8: the height field solved by a fixed-size Cholesky (the same to rounding)
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
      .input("left_out", "Cloud",
             "optional: points of the part not machined (cloud.trim_steep's left_out): where the ball touching the "
             "surface would cut into them it cannot reach (beside_left_out, reported, not counted in scallop and "
             "uncut), and no move may cut into them (a fail reason)", false)
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
    // what was not machined, as the guard keeps the ball off it: its obstacle points
    std::vector<Eigen::Vector3d> obstacles;
    if (ctx.has_input("left_out") && ctx.input<PointCloud>("left_out")->size()) {
      obstacles = obstacle_points(ctx.input<PointCloud>("left_out")->points, *cloud_height_field(*cloud));
      o.left_out = &obstacles;
    }
    try {
      if (ctx.has_input("loops")) o.loops = loop_polygons_xy(*ctx.input<BoundaryLoops>("loops"), cloud->points);
      // The rapids come down to a ball of r + lead_height above the part (post.link): checked,
      // as verify.py checks them, against the cloud's points raised by their uncertainty, beside
      // the simulation (their k-d tree over a million points takes 0.7 s on one thread).
      const double tol = std::max(o.chord, 1e-3);
      Simulation sim;
      RapidClearance rc, feed_left_out, rapids_left_out;
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
            // every move against what was not machined, as the rapids against the cloud
            if (!obstacles.empty()) {
              feed_left_out = rapid_clearance(obstacles, nullptr, feed, r, tol);
              rapids_left_out = rapid_clearance(obstacles, nullptr, rapids, r, tol);
            }
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
      if (o.left_out) {
        nlohmann::json& j = sim.report;
        char buf[240];
        for (const auto& [what, c] : {std::pair<const char*, const RapidClearance*>{"feed moves", &feed_left_out},
                                      {"rapids", &rapids_left_out}})
          if (c->through > 0) {
            std::snprintf(buf, sizeof buf,
                          "%zu %s cut into what was not machined (least clearance %.4g mm at (%.3f, %.3f, %.3f))",
                          c->through, what, c->least, c->at.x(), c->at.y(), c->at.z());
            j["fail_reasons"].push_back(buf);
            j["pass"] = false;
          }
        j["left_out_min_clearance"] = std::isfinite(std::min(feed_left_out.least, rapids_left_out.least))
                                          ? nlohmann::json(std::min(feed_left_out.least, rapids_left_out.least))
                                          : nlohmann::json();
        const auto& b = j["beside_left_out"];
        if (b["area_mm2"].get<double>() > 0)
          ctx.warn("not reachable by this ball beside what was not machined: " +
                   short_number(b["area_mm2"].get<double>()) + " mm2 (" +
                   short_number(100 * b["fraction"].get<double>()) + " % of the patch) from x " +
                   short_number(b["min"][0].get<double>()) + " to " + short_number(b["max"][0].get<double>()) + ", y " +
                   short_number(b["min"][1].get<double>()) + " to " + short_number(b["max"][1].get<double>()) +
                   ": a ball of radius " + short_number(r) + " touching the surface there would cut into it "
                   "(a smaller ball finishes it); not counted in the scallop and uncut figures");
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
