#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/path/ball_clearance_inputs.h"
#include "nodes/path/gouge_guard.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::path_nodes {

NodeDecl make_gouge_guard_node() {
  NodeDecl d;
  d.type = "path.gouge_guard";
  d.version = 22;  // 22: of left_out only the points apart from the patch by 3 spacings and above it (obstacle_points: a convex rim cut off by the trim is none); 21: a planned ball that reaches into left_out is moved sideways off it and set down on the patch again, where that clears it (at most r), else lifted (stop 92); 20: optional left_out, points the ball keeps clear of by half a spacing, where the field beyond the patch is not extrapolated; a lift that overshot is halved back to the lowest centre that clears (stop 92); 19: a foot in a hole within the rim band is on the surface, as beyond the outer loop (stop 90); 18: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 17: a point inserted into a move is raised until it reaches in by 3/4 of the move's tolerance, not until it touches (the clean canopy's zig-zag certificate passes); 16: the height field's quartic where its quadratic misfits (HeightFieldModel, kQuarticFrom); 15: the ring around a foot point only where the field's uncertainty may grow within a spacing (beyond the edge, or a fit that misfits its points by more than 1e-4 mm; the same programs on the example and 10 catalog and crest clouds, the guard 0.61-1.0 times as long); 14: where the gouge budget is a clearance (the surface known worse than 6 e, beyond a noisy cloud's edge) balls are lifted, and moves raised, half as much again clear of it, not to it (the noisy plane's band: 899 places unresolved -> 0, the guard 4.6 -> 1.7 s); 13: the foot search stops halving at 1e-4 mm, not 1e-7 (the same programs; the guard 11 % faster on the bundled example); 12: the ring of places checked around a foot beyond the edge at half a spacing and one (not also 2, 4 and 8: the same programs, the bundled example 1.6 s faster); 2: balls clear the surface raised by its uncertainty, grown at gaps beyond the edge; 4: a position may reach in by what the planner meant (chord budget) + e/4; 5: the height field's uncertainty counts its fit's misfit; 6: optional loops; 7: the height field solved by a fixed-size Cholesky (the same to rounding); 8: the band sampled above every cloud point within reach, not only at the foot point; 9: the foot search halves a step that ends farther from the ball (it swung off a crest tighter than the ball onto the flank), a move still too deep after its halvings is raised whole; 10: beyond the cloud's edge the band is checked around the foot too, out to 8 spacings (the uncertainty grows outward faster than the ball's distance); 11: moves held to the gouge budget, 0.9 e less 0.15 of the uncertainty where they reach deepest (the certificate samples the uncertainty between the places the guard checks)
                  // 3: fails where a ball would have to be lifted by more than 3 tool radii
  d.description =
      "checks every planned ball position and the middle of every move against the cloud's "
      "surface (its height field and its points); lifts the ball where it would cut in (on a "
      "denoised cloud: come closer than the surface's uncertainty) and reports where and by how much";
  d.input("path", "Toolpath", "the planned passes")
      .input("cloud", "Cloud", "the surface the passes must not cut into (seen from +z); with per-point uncertainty, balls clear it by that much (more at gaps beyond its edge)")
      .input("loops", "Loops", "optional: the patch's boundary loops (indices into 'cloud'); the surface is "
             "then checked everywhere inside their outline, as post.simulate does, also in gaps between "
             "rim points farther than the band kept without them", false)
      .input("band", "Cloud", "optional: cloud.surface_band of 'cloud' (computed here when not given)", false)
      .input("left_out", "Cloud", "optional: points of the part not machined (cloud.trim_steep's left_out: a steep "
             "wall beside the patch, a piece apart); the ball keeps clear of them, and off the patch where they "
             "lie the surface is not extrapolated", false)
      .output("toolpath", "Toolpath", "the passes, lifted where needed (lifted contact points are the ball's new touching points)")
      .output("report", "Report",
              "positions and moves checked, lifted and inserted positions, moves raised whole, places "
              "still cut in (unresolved: a lifted ball more than 1 % of e into the band, a move raised whole "
              "more than the chord tolerance), the deepest cut-in found and the highest lift, with where");
  d.options<GougeGuardOptions>()
      .number("tolerance", &GougeGuardOptions::tolerance, 0, 10, "mm",
              "how far the surface (raised by its uncertainty) may come inside the ball at a planned "
              "position before it is lifted; 0: a quarter of the path's chord error plus what the planner "
              "meant the ball to reach into that band there (min(uncertainty, 0.65 e - 0.15 uncertainty): the stock "
              "it keeps for the uncertainty covers only the rest of it)")
      .number("chord_tolerance", &GougeGuardOptions::chord_tolerance, 0, 10, "mm",
              "how far the surface (raised by its uncertainty) may come inside the ball in the middle "
              "of a move before a lifted point is inserted; 0: the gouge budget where the move reaches deepest, 0.9 of "
              "the path's chord error less 0.15 of the surface's uncertainty there (what the planner's chord "
              "budget lets the surface, raised by its uncertainty, reach in anywhere)")
      .integer("max_splits", &GougeGuardOptions::max_splits, 0, 10, "", "how often a move may be halved");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<Toolpath>("path");
    auto cloud = ctx.input<PointCloud>("cloud");
    GougeGuardOptions o = ctx.options<GougeGuardOptions>();
    o.progress = [&ctx](double f) { ctx.progress(f, "checking the ball against the surface"); };
    try {
      const auto check = ball_clearance_inputs(ctx, *cloud, path->tool_radius);
      auto res = guard_gouges(*path, *check->clearance, o);
      for (const auto& w : res.report["warnings"]) ctx.warn(w.get<std::string>());  // lifts, in one line each
      Report report;
      report.data = std::move(res.report);
      ctx.set("toolpath", std::move(res.path));
      ctx.set("report", std::move(report));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::path_nodes
