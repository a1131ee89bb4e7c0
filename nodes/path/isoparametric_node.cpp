#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/surface_band_input.h"
#include "nodes/path/isoparametric.h"
#include "nodes/path/part_fits_tool.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::path_nodes {

NodeDecl make_isoparametric_node() {
  NodeDecl d;
  d.type = "path.isoparametric";
  d.version = 22;  // 22: planar maps (param.planar, a raster): off the outline is off the patch, the rim pass planned first and the strips near it checked against its balls too; 21: a strip over the limit where no ball reaches says "uncut" (report: scallop null, uncut true), not a scallop of 1e+09 mm; 20: band passes into the holes, and a strip past a hole checked on the patch alone (stop 90); 19: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 18: the warnings of strips over the limit and of forward steps at their floor say where, and whether that lies beyond the cloud's outline; 17: the outline's uncertainty in the height field, the scallop height a whole-patch certificate needs there (report, warning, refusals' advice); 16: the height field takes a quartic over 40 points (of z over xy, or in the tangent frame where steep) where its quadratic misfits by more than 1e-3 / 3 mm (HeightFieldModel; the clean 3 mm crest's uncertainty 10 times smaller, its programs pass verify.py); 15: a strip whose secant stays over the limit at a zero step on two tries in a row is given up at once, keeping its first try at the formula's step (not built and checked again; the noisy freeform patch 7.6 -> 6.0 s); 14: a side step the secant cannot aim is halved from the fourth try on, not shrunk by sqrt(h / scallop), and a strip no step down to a 32nd of the formula's keeps is given up (such strips took 30 tries of 1-5 % each: the noisy freeform patch's plan 14.2 -> 7.9 s; strip_checks in the report; the clean programs checked the same); 13: closed passes cut a band beyond the outer loop (rim_band, three spacings);  3: margins for the cloud's uncertainty (surface_error); 4: and for the gap between its fit and the cloud's height field; 5: strips over the limit summarised in one warning (strips_over_limit_at), warnings said on the terminal, outline passes; 6: one rim pass through the outline's points, both patterns; holes (input loops) are not cut, a rim pass around each; 7: margins of one uncertainty (not 1.25 and 1.5), the fit gap added to it; 8: its strip checks see the height field's uncertainty with that fit's misfit (shape bias) counted; 9: the cusp found by regula falsi; 10: side steps shrunk by the secant; 11: the fits solved by a fixed-size Cholesky (the same answers to rounding); 12: margins planned with the smaller of a point's own uncertainty and its height field's (cloud.surface_band's, optional input band), the largest of that over the point's neighbours, the rim pass too; the gouge budget 0.9 e and the scallop limit h each less 0.15 of it (the certificate samples it between the places planned)
  d.description =
      "iso-parametric finishing passes from a UV-mapped cloud: zig-zag on a rectangle map, "
      "concentric on a disk map; forward step from the chord error, side step from the scallop "
      "height, checked between every two passes";
  d.input("cloud", "Cloud",
          "the points, with upward unit normals (and per-point uncertainty, kept as a margin)")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point (sampling scale)")
      .input("map", "UVMap", "uv of every point: rectangle for zigzag, disk for contour")
      .input("loops", "Loops",
             "the patch's boundary loops: holes (the loops after the outer one) are not cut, "
             "passes lift over them and a rim pass runs around each",
             false)
      .input("band", "Cloud",
             "cloud.surface_band of 'cloud' (its height field's uncertainty at each point: where it is "
             "smaller than the point's own, the margins are planned with it; computed here when not given)",
             false)
      .output("toolpath", "Toolpath", "the passes: contact points, normals, uv, in cutting order")
      .output("report", "Report",
              "passes, side and forward intervals, formula (4) use, predicted scallop and chord "
              "deviation, concave regions tighter than the tool");
  d.options<IsoparametricOptions>()
      .choice("pattern", &IsoparametricOptions::pattern, {"zigzag", "contour"},
              "zigzag: iso-u passes forward along v, alternating (rectangle map); contour: "
              "concentric circles from the boundary inwards (disk map)")
      .number("tool_radius", &IsoparametricOptions::tool_radius, 1e-3, 1e3, "mm", "ball-end cutter radius r")
      .number("scallop_height", &IsoparametricOptions::scallop_height, 1e-6, 1e2, "mm",
              "largest scallop height h allowed")
      .number("chord_error", &IsoparametricOptions::chord_error, 1e-6, 1e2, "mm", "largest chord deviation e allowed")
      .number("safety_factor", &IsoparametricOptions::safety_factor, 0.05, 1.0, "",
              "plan for safety_factor * h (margin for the cloud's own error)")
      .number("surface_error", &IsoparametricOptions::surface_error, 0.0, 1e2, "mm",
              "the cloud's surface is known to +- this (e.g. the scanner's accuracy); where "
              "the cloud's own per-point uncertainty (from cloud.denoise) is larger, that "
              "is used. The scallop is planned for h minus it, and the ball kept above the "
              "estimate by what the chord budget cannot absorb, so the limits hold on the "
              "real surface")
      .number("conformal_tolerance", &IsoparametricOptions::conformal_tolerance, 0.0, 89.0, "deg",
              "where r_u and r_v are further than this from orthogonal, the side step uses "
              "the corrected formula (4) instead of (3)")
      .number("max_segment", &IsoparametricOptions::max_segment, 1e-3, 1e3, "mm", "longest forward step")
      .integer("interpolation_k", &IsoparametricOptions::interpolation_k, 6, 64, "", "neighbours per local (u,v) fit")
      .integer("max_passes", &IsoparametricOptions::max_passes, 1, 1000000, "",
               "the work budget: more passes than this, estimated before planning (or met "
               "while planning), refuse with the estimate")
      .flag("outline", &IsoparametricOptions::outline, 
            "a last closed pass through the outline's own points, so the rim between pass "
            "ends and the outline's corners are cut")
      .number("rim_band", &IsoparametricOptions::rim_band, -1, 100, "mm",
              "with outline, closed passes offset outward from the outer loop cut this band beyond "
              "it, along the surface (the real outline lies beyond the cloud's outermost points, "
              "by up to 2.7 spacings on the catalog's clouds), and into each hole from its loop, "
              "no deeper than half its radius; -1: three of the cloud's spacings; 0: none");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto neighbors = ctx.input<Neighborhoods>("neighbors");
    auto map = ctx.input<UVMap>("map");
    IsoparametricOptions o = ctx.options<IsoparametricOptions>();
    o.progress = [&ctx](double f, const std::string& m) { ctx.progress(f, m); };
    IsoparametricResult res;
    try {
      if (auto m = part_narrower_than_ball(cloud->points, o.tool_radius); !m.empty()) throw std::invalid_argument(m);
      std::shared_ptr<const BoundaryLoops> loops;
      if (ctx.has_input("loops")) loops = ctx.input<BoundaryLoops>("loops");
      const auto band = surface_band_input(ctx, *cloud);
      res = plan_isoparametric(*cloud, *neighbors, *map, o, loops.get(), band ? &band->uncertainty : nullptr);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    for (const auto& w : res.report["warnings"]) ctx.warn(w.get<std::string>());
    Report report;
    report.data = std::move(res.report);
    ctx.set("toolpath", std::move(res.toolpath));
    ctx.set("report", std::move(report));
  };
  return d;
}

}  // namespace scallop::path_nodes
