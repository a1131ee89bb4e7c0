#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/mesh/simplify.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_simplify_node() {
  NodeDecl d;
  d.type = "mesh.simplify";
  d.version = 2;  // 2: max_valence (no fans of slivers along feature curves)
  d.description =
      "fewer triangles by CGAL's edge collapse (Garland-Heckbert quadrics), feature and border edges kept in place: "
      "a dense mesh made light enough for QuadriFlow";
  d.input("mesh", "Mesh", "a manifold triangle mesh (mesh.repair); its feature_edges (mesh.sharp_edges) are kept")
      .output("mesh", "Mesh",
              "at most target_faces triangles (fewer collapses where a face would turn over, a feature blocks or a "
              "vertex would get more than max_valence edges), "
              "vertices renumbered, feature_edges the input's; normals and labels dropped")
      .output("report", "Report",
              "{faces_before, faces_after, vertices_before, vertices_after, feature_edges, border_edges (both kept), "
              "max_distance (mm, largest distance from an input vertex to the output), max_valence (the most edges at "
              "one output vertex)}");
  d.options<SimplifyOptions>().integer("target_faces", &SimplifyOptions::target_faces, 4, 100000000, "",
                                       "triangles to keep; a mesh with no more passes unchanged")
      .integer("max_valence", &SimplifyOptions::max_valence, 6, 1000000, "",
               "no collapse leaves a vertex with more edges than this: a feature curve's vertices never move, and "
               "without a cap their neighbours collapse into them (fans of slivers, a collapse that costs more with "
               "each)");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    SimplifyReport r;
    Mesh out;
    try {
      out = simplify_mesh(*mesh, ctx.options<SimplifyOptions>(), r);
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("mesh.simplify: ") + e.what());
    }
    Report report;
    report.data = {{"faces_before", r.faces_before},     {"faces_after", r.faces_after},
                   {"vertices_before", r.vertices_before}, {"vertices_after", r.vertices_after},
                   {"feature_edges", r.feature_edges},   {"border_edges", r.border_edges},
                   {"max_distance", r.max_distance},     {"max_valence", r.max_valence}};
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(out));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
