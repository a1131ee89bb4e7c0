#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/geom/point_text.h"
#include "nodes/geom/bspline_surface.h"
#include "nodes/path/contour_grid.h"
#include "nodes/surface/fit_bspline.h"
#include "nodes/types/mesh.h"
#include "nodes/types/document.h"
#include "nodes/types/surfaces.h"
#include "nodes/types/toolpath.h"

namespace scallop::path_nodes {

NodeDecl make_contour_grid_node() {
  NodeDecl d;
  d.type = "path.contour_grid";
  d.version = 9;  // 9: the report says how tight a concave patch curves (concave_radius_min) and a warning what smaller ball would follow it; 8: the patches' warnings said in a line each kind, not a line each patch; 4: normals held within the patch's cap (machining_surface); 5: each side starts from the share of its formula step the last contour kept; 6: steps aim at 0.94 h, not 0.99 h; 7: each contour held to h less the surface's distance from the part in its ring, not in the whole patch
  d.description =
      "contour-parallel passes on every B-spline patch (the second paper's Algorithm 1): nested rectangles of the "
      "patch's (u, v) square, each side stepped in from the scallop limit and the scallop between every two "
      "contours evaluated on the surface";
  d.input("surfaces", "Surfaces", "the patches (surface.fit_bspline), each machined along its own direction")
      .input("part", "Mesh",
             "the part's own mesh, what the programs are measured against: each contour's scallop is held to h less "
             "the surface's largest distance from it in the ring the contour's sides step across (at most h / 2; more "
             "is warned about)",
             false)
      .output("toolpath", "Toolpath",
              "the contours of every patch in the part's frame (patch by patch, outermost first, each closed), "
              "normals turned to the patch's direction")
      .output("report", "Report",
              "{patches: [{patch, contours, points, u_step_min/max, v_step_min/max (parameter units), "
              "side_steps_shrunk, scallop_max and chord_max (found by the checks, mm), unreachable_samples, "
              "grid_lines, scallop_limit_min (the least contour limit, mm), part_distance_max (mm, with part)}], contours, "
              "points, scallop_max, "
              "chord_max}");
  d.options<ContourGridOptions>()
      .number("tool_radius", &ContourGridOptions::tool_radius, 1e-3, 1e3, "mm", "ball-end cutter radius r")
      .number("scallop_height", &ContourGridOptions::scallop_height, 1e-6, 1e2, "mm", "largest scallop height h")
      .number("chord_error", &ContourGridOptions::chord_error, 1e-6, 1e2, "mm", "largest chord deviation e")
      .number("max_segment", &ContourGridOptions::max_segment, 1e-3, 1e3, "mm", "longest forward step")
      .integer("side_samples", &ContourGridOptions::side_samples, 2, 10000, "",
               "points per side where the side step is computed (Algorithm 1's k)")
      .integer("max_contours", &ContourGridOptions::max_contours, 1, 1000000, "",
               "more contours than this on one patch: refused, with where");
  d.run = [](NodeContext& ctx) {
    auto surfaces = ctx.input<Surfaces>("surfaces");
    const ContourGridOptions o = ctx.options<ContourGridOptions>();
    if (!(o.scallop_height < o.tool_radius))
      throw NodeError("path.contour_grid: scallop_height must be smaller than tool_radius");
    const std::size_t np = surfaces->patches.size();
    if (np == 0) throw NodeError("path.contour_grid: there are no patches");
    // The surface is not the part: where it lies d off the part's faces (a facet's sag on a curved
    // part, the fit between vertices, a rim over a rounded edge or the envelope's allowance beside
    // one), the scallop on the part can be up to d more: each contour is held to h less the
    // largest d near the ring its sides step across, never less than h / 2 (the patch's largest
    // d held 118 of the block's 142 patches to h / 2 all over: 3 376 contours, 3 222 now).
    std::vector<SurfaceDistanceGrid> part_distance(np);
    if (ctx.has_input("part")) part_distance = surface_distance_grids(*surfaces, *ctx.input<Mesh>("part"));
    std::vector<ContourGridResult> results(np);
    std::vector<std::string> errors(np);
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(std::size_t(0), np, [&](std::size_t p) {
      try {
        const SurfacePatch& sp = surfaces->patches[p];
        const BSplinePatch patch = machining_surface(sp);
        ContourGridOptions patch_options = o;
        if (!part_distance[p].distance.empty())
          patch_options.scallop_limit = [&grid = part_distance[p], h = o.scallop_height](double u0, double u1, double v0,
                                                                                        double v1) {
            return h - std::min(grid.max_near(u0, u1, v0, v1), h / 2);
          };
        results[p] = plan_contour_grid(patch, patch_options);
      } catch (const std::invalid_argument& e) {
        errors[p] = e.what();
      }
      ctx.progress(double(++done) / double(np), "contours of patch " + std::to_string(p));
    });
    for (std::size_t p = 0; p < np; ++p)
      if (!errors[p].empty()) throw NodeError("path.contour_grid: patch " + std::to_string(p) + ": " + errors[p]);

    Toolpath tp;
    tp.tool_radius = o.tool_radius;
    tp.scallop_height = o.scallop_height;
    tp.chord_error = o.chord_error;
    tp.pattern = "contour_grid";
    nlohmann::json patches = nlohmann::json::array();
    std::size_t contours = 0, points = 0;
    double scallop_max = 0, chord_max = 0;
    // What the patches warn of, a line each kind (the face bust's 78 patches had said it in 72
    // lines), the list in the report.
    std::size_t off_part = 0, off_worst = 0, stuck = 0, tight = 0, tight_worst = 0;
    double off_max = 0, tight_radius = INFINITY;
    std::string first_stuck;
    for (std::size_t p = 0; p < np; ++p) {
      nlohmann::json r = results[p].report;
      r["patch"] = p;
      if (ctx.has_input("part")) {
        const std::vector<double>& d = part_distance[p].distance;
        const double farthest = d.empty() ? 0.0 : *std::max_element(d.begin(), d.end());
        r["part_distance_max"] = farthest;
        if (farthest > o.scallop_height / 2) {
          ++off_part;
          if (farthest > off_max) off_max = farthest, off_worst = p;
        }
      }

      if (r.contains("concave_radius_min")) {
        ++tight;
        if (const double radius = r["concave_radius_min"].get<double>(); radius < tight_radius)
          tight_radius = radius, tight_worst = p;
      }
      contours += r["contours"].get<std::size_t>();
      points += r["points"].get<std::size_t>();
      scallop_max = std::max(scallop_max, r["scallop_max"].get<double>());
      chord_max = std::max(chord_max, r["chord_max"].get<double>());
      if (r.contains("warning") && stuck++ == 0) first_stuck = "patch " + std::to_string(p) + ": " + r["warning"].get<std::string>();
      patches.push_back(std::move(r));
      for (auto& pass : results[p].passes) tp.passes.push_back(std::move(pass));
    }
    if (off_part > 0)
      ctx.warn(std::to_string(off_part) + " of " + std::to_string(np) + " patches lie more than h / 2 off the part's "
               "faces (up to " + short_number(off_max) + " mm, patch " + std::to_string(off_worst) +
               "; the report's part_distance_max per patch): their contours there are planned to h / 2 and may "
               "leave more than h on the part (the certificate measures it)");
    // (a radius under 0.01 mm is a crease the patch folds along, not a curve a ball follows)
    if (tight > 0)
      ctx.warn(std::to_string(tight) + " of " + std::to_string(np) + " patches curve concave tighter than the tool (radius " +
               short_number(o.tool_radius) + " mm) across their contours, the tightest patch " + std::to_string(tight_worst) +
               (tight_radius >= 0.01 ? " to a radius of " + short_number(tight_radius) + " mm, which a smaller ball would follow"
                                     : " in a concave crease (radius " + short_number(tight_radius, 2) + " mm) that no ball follows") +
               " (the report's concave_radius_min per patch): this ball is kept off such places, and the certificate "
               "measures what it leaves");
    if (stuck == 1) ctx.warn(first_stuck);
    if (stuck > 1)
      ctx.warn(std::to_string(stuck) + " patches have contours whose scallop stayed above h after 60 shrinks (" +
               first_stuck + "; the report's warning per patch)");
    Report report;
    report.data = {{"patches", std::move(patches)}, {"contours", contours},       {"points", points},
                   {"scallop_max", scallop_max},      {"chord_max", chord_max}};
    ctx.set("report", std::move(report));
    ctx.set("toolpath", std::move(tp));
  };
  return d;
}

}  // namespace scallop::path_nodes
