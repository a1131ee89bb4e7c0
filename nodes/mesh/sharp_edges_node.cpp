#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/sharp_edges.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_sharp_edges_node() {
  NodeDecl d;
  d.type = "mesh.sharp_edges";
  d.version = 2;  // 2: fold_angle
  d.description =
      "sharp edges (faces' normals more than `angle` apart) chained into feature curves between "
      "corners; sets the mesh's feature edges";
  d.input("mesh", "Mesh", "a polygon mesh")
      .output("mesh", "Mesh", "the same mesh, its feature edges the sharp edges (any it had replaced)")
      .output("report", "Report",
              "{angle_deg, sharp_edges, folds (edges turning by more than fold_angle), curves, closed_curves, corners, length (mm, all sharp "
              "edges), boundary_edges and non_manifold_edges (not rated), feature_curves: "
              "[{vertices (indices along the curve), closed, length}], corner_vertices}")
      .param_float("angle", 50.0, 0, 179.9, "deg",
                   "an edge is sharp when the normals of its two faces differ by more than this "
                   "(50 as in the paper; 90 on a cube's edges)")
      .param_float("fold_angle", 180.0, 0.1, 180, "deg",
                   "an edge whose faces turn by more than this is a fold of the mesh (a face turned over), not "
                   "an edge of the part: counted, not sharp (180: none; the cloud graphs set 150, for the slivers "
                   "mesh.sharpen can leave turned over beside an edge)");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    const double angle = ctx.number("angle");
    SharpEdges s;
    try {
      s = sharp_edges(*mesh, mesh_edges(*mesh), angle, ctx.number("fold_angle"));
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("mesh.sharp_edges: ") + e.what());
    }
    nlohmann::json curves = nlohmann::json::array();
    std::size_t closed = 0;
    for (const auto& c : s.curves) {
      curves.push_back({{"vertices", c.vertices}, {"closed", c.closed}, {"length", c.length}});
      if (c.closed) ++closed;
    }
    Report report;
    report.data = {{"angle_deg", angle},
                   {"sharp_edges", s.edges.size()},
                   {"folds", s.folds},
                   {"curves", s.curves.size()},
                   {"closed_curves", closed},
                   {"corners", s.corners.size()},
                   {"length", s.length},
                   {"boundary_edges", s.boundary_edges},
                   {"non_manifold_edges", s.non_manifold_edges},
                   {"feature_curves", std::move(curves)},
                   {"corner_vertices", s.corners}};
    Mesh out = *mesh;
    out.feature_edges = std::move(s.edges);
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(out));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
