#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/self_crossings.h"
#include "nodes/mesh/setup_base.h"
#include "nodes/post/simulate_part.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_simulate_part_node() {
  NodeDecl d;
  d.type = "post.simulate_part";
  d.version = 19;  // 19: the refinement also seeds from every cell's highest (refinement_seeds.h); 18: a failing interior maximum where no clamping comes down says so (the programs\' unreached places); 17: where the mesh is the part itself (no input cloud), no tangle margin (tangle_margin); 2: the worst places begin with the moves that reach into the part; 3: faces folded onto a neighbour leave the side to the rays; 4: samples in strips along each face's longest edge, by area, as verify_part.py; 5: refinement seeded from the highest 1 %; 6: and from the samples a ball of 0.9 r reaches; 7: twice as densely where the edge of the reach may cross a seed's square; 8: the report says where the interior maximum stands (scallop_max_interior_at); 9: edge_uncertainty_edges, the cloud's points checked for gouges; 10: and for where the outer mesh does not hold them (gouge_unbounded_*); 11: faces of the outer mesh its moves turned over leave the side to the rays; 12: the reach radius of an unreachable place to r / 32768 (was r / 2^30); 13: faces of the outer mesh turned more than 10 degrees leave the side to the rays (was 90); 14: where the part's mesh crosses itself, a ball passing within r + 3/4 of the tangle margin of its tangled faces fails it (crossing_pairs, tangled_faces, tangle_*); 15: and its tangled faces leave the side to the rays; 16: a failing interior maximum says where, and over how much of the part
  d.description =
      "the certificate of a whole part cut in several clampings: every setup's program taken back to the part, "
      "scallop left over the whole mesh, gouge and rapids against it (verify_part.py's definitions)";
  d.input("programs", "SetupPaths", "the programs and their part_to_machine (post.setup_programs)")
      .input("mesh", "Mesh", "the part, faces outward (the mesh the programs were kept off)")
      .input("base", "Report",
             "mesh.setup_base's report: faces within base_angle of its base_direction sit on the table and are not "
             "measured; absent: every face is measured", false)
      .input("outer", "Mesh",
             "the part's outer bound (mesh.cloud_envelope's outer): gouge and rapids are measured against it; "
             "absent: against `mesh`", false)
      .input("inner", "Mesh",
             "the part's inner bound, `mesh` with its vertices moved (mesh.cloud_envelope's inner): each sample's "
             "scallop is traced from its place there; samples are still placed and classified on `mesh`", false)
      .input("cloud", "Cloud",
             "the points the mesh was made from: a point inside a feed ball is the part cut away, whatever the meshes "
             "say (gouge_max_cloud, gouge_cloud_at, cloud_points_cut; it counts in gouge_max); with `outer`, a point "
             "outside it by x > the gouge tolerance that a ball passes within r + x of leaves the gouge there unbounded "
             "and the certificate failed (gouge_unbounded_points, gouge_unbounded_max, gouge_unbounded_at)", false)
      .output("report", "Report",
              "pass (verify_part.py's rule: interior scallop <= 1.01 h, gouge <= max(e, 0.001), nothing uncut, no rapid "
              "through the part, and no ball centre within r + 3/4 of tangle_margin of the faces where `mesh` crosses itself or beside "
              "those turned into the part: crossing_pairs, tangled_faces, tangle_margin, "
              "tangle_samples_reached, tangle_reached_at), fail_reasons, scallop/uncut figures for the whole part and its interior, gouge, "
              "rapids, base and unreachable fractions, per setup figures, the unreachable places with the largest "
              "tool radius that reaches each, the 10 worst places")
      .output("simulation", "Simulation", "what the programs left at every measured sample, with its face (post.render)")
      .param_float("surface_uncertainty", 0, 0, 100, "mm",
                   "how far the real part may lie off the mesh (0 for a CAD mesh): scallop and gouge become bounds")
      .param_float("base_angle", 10, 0, 90, "deg", "faces within this of the base direction are on the table")
      .param_float("feature_angle", 30, 0, 180, "deg",
                   "interior = farther than the margin from borders and from edges whose faces turn by more than this");
  d.options<PartSimulateOptions>()
      .number("spacing", &PartSimulateOptions::spacing, 0, 100, "mm", "sample spacing; 0: sqrt(8 r h)/8")
      .number("margin", &PartSimulateOptions::margin, 0, 1000, "mm",
              "interior = farther than this from sharp edges and borders; 0: sqrt(8 r h)")
      .number("edge_uncertainty", &PartSimulateOptions::edge_uncertainty, 0, 100, "mm",
              "how far the mesh's edges may lie off the part's (a mesh made from a cloud): the interior starts this "
              "much nearer them, so that it holds all of the part's own")
      .number("edge_uncertainty_edges", &PartSimulateOptions::edge_uncertainty_edges, 0, 100, "mean edge lengths",
              "the same in mean edge lengths of `mesh` (a reconstruction's are its cloud's spacing); the larger counts")
      .integer("max_samples", &PartSimulateOptions::max_samples, 1000, 100000000, "",
               "the spacing is raised to stay below this many samples")
      .number("tangle_margin", &PartSimulateOptions::tangle_margin, -1, 1000, "mm",
              "how much farther than r no ball centre may come to the faces where `mesh` crosses itself: -1 twice "
              "those faces' mean edge where the mesh was made from a cloud (input cloud), none where the mesh is the "
              "part itself (a CAD mesh whose facets fold)");
  d.run = [](NodeContext& ctx) {
    auto programs = ctx.input<SetupPaths>("programs");
    auto mesh = ctx.input<Mesh>("mesh");
    PartSimulateOptions o = ctx.options<PartSimulateOptions>();
    o.surface_uncertainty = ctx.number("surface_uncertainty");
    o.base_angle = ctx.number("base_angle");
    o.feature_angle = ctx.number("feature_angle");
    // (as post.setup_programs keeps the balls off: the reconstruction's rule only for a mesh made from a cloud)
    o.tangle_margin = tangle_margin_for(o.tangle_margin, ctx.has_input("cloud"));
    if (ctx.has_input("base")) {
      try {
        o.base_normal = base_direction_of(ctx.input<Report>("base")->data);
      } catch (const std::invalid_argument& e) {
        throw NodeError(e.what());
      }
    }
    if (programs->setups.empty()) throw NodeError("the input 'programs' has no setup");
    o.unreached_at = programs->unreached_at;
    o.unreached_area = programs->unreached_area;
    o.unreached_by_any_direction = programs->unreached_by_any_direction;
    std::vector<PartSetupCut> cuts;
    const LinkedPath& first = programs->setups.front().path;
    o.tool_radius = first.tool_radius, o.scallop = first.scallop_height, o.chord = first.chord_error;
    for (const SetupPath& s : programs->setups) {
      if (s.path.tool_radius != o.tool_radius) {
        char text[120];
        std::snprintf(text, sizeof text, "' uses a tool of radius %g mm, the first %g mm: one tool for the whole part",
                      s.path.tool_radius, o.tool_radius);
        throw NodeError("setup '" + s.name + text);
      }
      PartSetupCut& cut = cuts.emplace_back();
      cut.name = s.name;
      // Ball centres (tip + r z) taken back to the part: p = R^T (x - t).
      const Eigen::Vector3d up(0, 0, s.path.tool_radius);
      auto to_part = [&](const Eigen::Vector3d& tip) { return Eigen::Vector3d(s.rotation.transpose() * (tip + up - s.translation)); };
      for (std::size_t i = 1; i < s.path.moves.size(); ++i) {
        const Move& m0 = s.path.moves[i - 1];
        const Move& m1 = s.path.moves[i];
        (m1.kind == MoveKind::Rapid ? cut.rapid : cut.feed).push_back({to_part(m0.tip), to_part(m1.tip)});
      }
    }
    try {
      const auto outer = ctx.has_input("outer") ? ctx.input<Mesh>("outer") : nullptr;
      const auto inner = ctx.has_input("inner") ? ctx.input<Mesh>("inner") : nullptr;
      const auto cloud = ctx.has_input("cloud") ? ctx.input<PointCloud>("cloud") : nullptr;
      Simulation sim = simulate_part(*mesh, cuts, o, [&](double f) { ctx.progress(f, "simulating the part"); }, outer.get(),
                                     inner.get(), cloud ? &cloud->points : nullptr);
      Report rep;
      rep.data = sim.report;
      ctx.set("report", std::move(rep));
      ctx.set("simulation", std::move(sim));
    } catch (const std::invalid_argument& ex) {
      throw NodeError(std::string("post.simulate_part: ") + ex.what());
    }
  };
  return d;
}
}  // namespace scallop::post_nodes
