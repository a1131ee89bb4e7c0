#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/mesh/quad_remesh.h"
#include "nodes/mesh/topology_report.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_quad_remesh_node() {
  NodeDecl d;
  d.type = "mesh.quad_remesh";
  d.version = 4;  // 4: the next seeds tried when the quads are not usable; seeds_tried
  d.description =
      "remeshes into quads aligned with the sharp features by QuadriFlow, run in Blender (Debian package blender) "
      "as a separate process";
  d.input("mesh", "Mesh", "a manifold, consistently oriented mesh (mesh.repair); its feature_edges, when set, are the "
                          "feature curves measured")
      .output("mesh", "Mesh",
              "the quad mesh, faces counter-clockwise seen from outside as the input's, manifold; feature_edges its "
              "sharp edges at angle")
      .output("report", "Report",
              "{target_faces, faces, quads, quad_fraction, vertices, extraordinary_points (interior vertices of "
              "valence other than 4), mean_edge_length (mm), sharp_edges, feature_source (feature_edges or angle), "
              "feature_length (mm, the input's feature curves), feature_length_on_quad_edges, feature_share (pieces of "
              "the input's feature edges, at most a quarter of the mean edge long, whose midpoint lies within "
              "feature_tolerance mean edges of an output sharp edge), feature_tolerance_mm, "
              "feature_length_below_60 (QuadriFlow keeps only edges sharper than 60 degrees), "
              "doublets_zipped (QuadriFlow's triangles, written as quads of no area, joined away), holes_filled "
              "(three-edge holes where it left a triangle out, closed keeping all quads), quads_split (by that), "
              "repeated_corners_removed, triangles_paired (two triangles a repeated corner left, sharing an edge, "
              "made one quad), triangles_opened (a lone one, closed as a hole), faces_dropped, components_reversed, "
              "seconds, quadriflow_seconds, "
              "blender_version, blender, seed (the one used), seeds_tried, snap: {corners, feature_vertices, surface_vertices (moved onto the input's "
              "corners, feature curves, faces), kept, off_surface_max (mm, before), moved_max (mm)}, topology}");
  d.options<QuadRemeshOptions>()
      .integer("target_faces", &QuadRemeshOptions::target_faces, 1, 10000000, "",
               "quads asked of QuadriFlow (it gives about as many)")
      .number("target_edge_length", &QuadRemeshOptions::target_edge_length, 0, 1e6, "mm",
              "> 0: sets target_faces to the mesh's area over its square")
      .integer("seed", &QuadRemeshOptions::seed, 0, 2147483647, "", "QuadriFlow's random seed (same seed, same quads)")
      .integer("tries", &QuadRemeshOptions::tries, 1, 100, "",
               "seeds tried in turn (seed, seed + 1, ...) while QuadriFlow's quads tear holes or are not a manifold; "
               "the report says which was used")
      .number("angle", &QuadRemeshOptions::angle_deg, 0, 179.9, "deg",
              "sharp edges (faces' normals further apart; 50 as in the paper): the output's feature edges, and the "
              "input's feature curves when it has no feature_edges")
      .number("feature_tolerance", &QuadRemeshOptions::feature_tolerance, 0.001, 1, "",
              "a feature piece lies on quad edges within this many mean edge lengths of an output sharp edge")
      .flag("snap", &QuadRemeshOptions::snap,
            "move the quads' vertices back onto the input, corners onto its corners and feature vertices onto its "
            "feature curves, each by at most the mean edge length (QuadriFlow leaves them off near features)")
      .text("blender", &QuadRemeshOptions::blender,
            "Blender's executable; empty: the environment variable SCALLOP_BLENDER, else blender on PATH")
      .number("timeout", &QuadRemeshOptions::timeout_s, 1, 86400, "s", "Blender is stopped after this long, and the next seed tried on the input simplified to 3/4 of its triangles "
              "(QuadriFlow's sharp-feature flow now and then never ends where a slightly different input takes seconds)");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    const QuadRemeshOptions o = ctx.options<QuadRemeshOptions>();
    QuadRemeshReport r;
    Mesh out;
    try {
      out = quad_remesh(*mesh, o, r, [&](double f, const std::string& what) { ctx.progress(f, what); });
    } catch (const BlenderMissing& e) {
      throw NodeError(std::string("mesh.quad_remesh ") + e.what());
    } catch (const std::exception& e) {
      throw NodeError(std::string("mesh.quad_remesh: ") + e.what());
    }
    Report report;
    report.data = {{"target_faces", r.target_faces},
                   {"faces", r.faces},
                   {"quads", r.quads},
                   {"quad_fraction", r.quad_fraction},
                   {"vertices", r.vertices},
                   {"extraordinary_points", r.extraordinary_points},
                   {"mean_edge_length", r.mean_edge_length},
                   {"sharp_edges", r.sharp_edges},
                   {"feature_source", r.feature_source},
                   {"feature_length", r.feature_length},
                   {"feature_length_on_quad_edges", r.feature_length_on_quad_edges},
                   {"feature_share", r.feature_share},
                   {"feature_tolerance_mm", r.feature_tolerance_mm},
                   {"feature_length_below_60", r.feature_length_below_60},
                   {"doublets_zipped", r.doublets_zipped},
                   {"holes_filled", r.holes_filled},
                   {"quads_split", r.quads_split},
                   {"repeated_corners_removed", r.repeated_corners_removed},
                   {"triangles_paired", r.triangles_paired},
                   {"triangles_opened", r.triangles_opened},
                   {"faces_dropped", r.faces_dropped},
                   {"snap",
                    {{"corners", r.snap.corners},
                     {"feature_vertices", r.snap.feature_vertices},
                     {"surface_vertices", r.snap.surface_vertices},
                     {"kept", r.snap.kept},
                     {"off_surface_max", r.snap.off_surface_max},
                     {"moved_max", r.snap.moved_max}}},
                   {"components_reversed", r.components_reversed},
                   {"seconds", r.seconds},
                   {"quadriflow_seconds", r.quadriflow_seconds},
                   {"blender_version", r.blender_version},
                   {"blender", r.blender.string()},
                   {"seed", r.seed},
                   {"seeds_tried", r.seeds_tried},
                   {"topology", topology_report(out)}};
    if (!r.warning.empty()) ctx.warn(r.warning);
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(out));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
