#include <algorithm>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/surface/fit_bspline.h"
#include "nodes/surface/tessellate.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/segments.h"

namespace scallop::surface_nodes {

NodeDecl make_fit_bspline_node() {
  NodeDecl d;
  d.type = "surface.fit_bspline";
  d.version = 2;
  d.description =
      "fits each sharp height field with a bicubic B-spline on the unit square (the patch's quad grid as its "
      "parameters, thin-plate smoothing relaxed until every grid vertex is within tolerance); patches sharing a "
      "whole border share its curve; given the part's mesh, the grids are made twice as fine, their new vertices "
      "on the part, until the surfaces lie within part_tolerance of it";
  d.input("segments", "Segments", "the patches (mesh.segment)")
      .input("base", "Report", "mesh.setup_base's report, copied into this report as base", false)
      .input("quads", "Report", "mesh.quad_remesh's report, copied into this report as quad_mesh", false)
      .input("part", "Mesh",
             "the mesh the quads were made from, its feature_edges set (mesh.sharp_edges): the surfaces are refined "
             "toward it",
             false)
      .output("surfaces", "Surfaces", "per patch its B-spline surface, direction and fit figures")
      .output("mesh", "Mesh", "the surfaces sampled as quads, face label = patch, patch outlines as feature edges")
      .output("report", "Report",
              "{tolerance, patches: [{direction, min_normal_dot, grid: [rows, cols], poles: [u, v], degree: [u, v], "
              "fit_max_error, fit_mean_error, smoothing, mesh_distance_max (surface to the quad mesh: facet sag and any "
              "bulge between vertices)}], fit_max_error and mesh_distance_max, patches_bulging (farther from their quads than a quarter edge) (largest over the patches), "
              "patches_over_tolerance, shared_borders, shared_edges, boundary_gap_max (mm, between neighbouring "
              "surfaces along shared mesh edges) and between which patches, base_direction; base and quad_mesh when given; "
              "with part: subdivisions, part_distance_before and part_distance_max (mm, the farthest surface from the "
              "part before and after), per patch part_distance_max}");
  d.options<FitBSplineOptions>()
      .number("tolerance", &FitBSplineOptions::tolerance, 1e-9, 100, "mm",
              "largest distance from a grid vertex to its point on the surface (a quarter of the chord error: "
              "0.00125 for e = 0.005)")
      .number("smoothing", &FitBSplineOptions::smoothing, 0, 1, "",
              "the thin-plate weight alpha tried first (relative to the fitting term); 0: interpolate")
      .integer("refinements", &FitBSplineOptions::refinements, 0, 30, "",
               "tries with alpha divided by 10 each before interpolating")
      .integer("subdivisions", &FitBSplineOptions::subdivisions, 0, 4, "",
               "with part: the most times the grids are made twice as fine (each time 4 times the vertices)")
      .number("part_tolerance", &FitBSplineOptions::part_tolerance, 1e-9, 100, "mm",
              "with part: the grids are refined while a surface lies farther than this from the part");
  d.param_int("samples", 16, 1, 256, "", "quads per patch side in the output mesh");
  d.run = [](NodeContext& ctx) {
    auto segments = ctx.input<Segments>("segments");
    const FitBSplineOptions o = ctx.options<FitBSplineOptions>();
    if (segments->patches.empty()) throw NodeError("the segments hold no patch: nothing to fit");
    FitStats stats;
    Surfaces s;
    try {
      const Mesh* part = ctx.has_input("part") ? ctx.input<Mesh>("part").get() : nullptr;
      s = fit_surfaces(*segments, o, &stats, [&](double f, const std::string& m) { ctx.progress(f, m); }, part);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    nlohmann::json patches = nlohmann::json::array();
    double worst = 0, farthest = 0;
    std::size_t over = 0;
    for (std::size_t i = 0; i < s.patches.size(); ++i) {
      const SurfacePatch& p = s.patches[i];
      worst = std::max(worst, p.fit_max_error);
      farthest = std::max(farthest, p.mesh_distance_max);
      over += p.fit_max_error > o.tolerance;
      patches.push_back({{"direction", {p.direction.x(), p.direction.y(), p.direction.z()}},
                         {"min_normal_dot", p.min_normal_dot},
                         {"grid", {p.rows, p.cols}},
                         {"poles", {p.surface.poles_u, p.surface.poles_v}},
                         {"degree", {p.surface.degree_u, p.surface.degree_v}},
                         {"fit_max_error", p.fit_max_error},
                         {"fit_mean_error", p.fit_mean_error},
                         {"smoothing", p.smoothing},
                         {"mesh_distance_max", p.mesh_distance_max}});
      if (!stats.part_distance.empty()) patches.back()["part_distance_max"] = stats.part_distance[i];
    }
    // A facet's sag stays under an eighth of its edge wherever the part curves no tighter than the
    // quads are long; a surface farther from its quads than a quarter edge bulges between them.
    std::size_t bulging = 0, worst_patch = 0;
    double worst_ratio = 0;
    for (std::size_t i = 0; i < s.patches.size(); ++i) {
      const SegmentPatch& g = segments->patches[i];
      double length = 0;
      std::size_t edges = 0;
      for (std::uint32_t r = 0; r < g.rows; ++r)
        for (std::uint32_t c = 0; c < g.cols; ++c) {
          const Eigen::Vector3d& v = segments->mesh.vertices[g.at(r, c)];
          if (c + 1 < g.cols) length += (segments->mesh.vertices[g.at(r, c + 1)] - v).norm(), ++edges;
          if (r + 1 < g.rows) length += (segments->mesh.vertices[g.at(r + 1, c)] - v).norm(), ++edges;
        }
      const double ratio = s.patches[i].mesh_distance_max / (length / double(edges));
      bulging += ratio > 0.25;
      if (ratio > worst_ratio) worst_ratio = ratio, worst_patch = i;
    }
    if (bulging > 0)
      ctx.warn(std::to_string(bulging) + " of " + std::to_string(s.patches.size()) +
               " patches bulge from their quads by more than a quarter of a quad's edge (worst: patch " +
               std::to_string(worst_patch) + ", " + std::to_string(s.patches[worst_patch].mesh_distance_max) +
               " mm): more quads, or a fit to the dense mesh, would follow the part better");
    if (over > 0)
      ctx.warn(std::to_string(over) + " of " + std::to_string(s.patches.size()) +
               " patches fit their grid less closely than the tolerance");
    Report report;
    report.data = {{"tolerance", o.tolerance},
                   {"patches", std::move(patches)},
                   {"fit_max_error", worst},
                   {"mesh_distance_max", farthest},
                   {"patches_over_tolerance", over},
                   {"patches_bulging", bulging},
                   {"shared_borders", stats.shared_borders},
                   {"shared_edges", stats.shared_edges},
                   {"boundary_gap_max", stats.boundary_gap_max},
                   {"boundary_gap_between", {stats.boundary_gap_patch_a, stats.boundary_gap_patch_b}}};
    if (ctx.has_input("part")) {
      report.data["subdivisions"] = stats.subdivisions;
      report.data["part_distance_before"] = stats.part_distance_before;
      report.data["part_distance_max"] = stats.part_distance_after;
    }
    const Eigen::Vector3d& b = s.base_direction;
    report.data["base_direction"] = {b.x(), b.y(), b.z()};
    // One report a person reads for the whole segmentation: the base and the quads it rests on.
    if (ctx.has_input("base")) report.data["base"] = ctx.input<Report>("base")->data;
    if (ctx.has_input("quads")) report.data["quad_mesh"] = ctx.input<Report>("quads")->data;
    ctx.set("mesh", tessellate_surfaces(s, static_cast<int>(ctx.integer("samples"))));
    ctx.set("report", std::move(report));
    ctx.set("surfaces", std::move(s));
  };
  return d;
}

}  // namespace scallop::surface_nodes
