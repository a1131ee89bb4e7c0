#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/segment.h"
#include "nodes/types/document.h"
#include "nodes/types/segments.h"

namespace scallop::mesh_nodes {

NodeDecl make_segment_node() {
  NodeDecl d;
  d.type = "mesh.segment";
  d.version = 2;  // 2: no join where the union's border would turn more than 30 degrees
  d.description =
      "cuts a quad mesh into sharp height fields (the paper's MST of extraordinary points and clipping edges by "
      "priority): rectangles of the quad grid with the sharp edges on their borders, each a height field along a "
      "machining direction of its own";
  d.input("mesh", "Mesh", "a manifold quad mesh, faces outward (mesh.quad_remesh; the base removed by mesh.setup_base)")
      .input("base", "Report", "mesh.setup_base's report: its base_direction is kept with the segments", false)
      .output("segments", "Segments", "the mesh with a patch label per face; per patch its grid, direction, smallest n.d")
      .output("report", "Report",
              "{patches: [{direction, min_normal_dot, rows, cols, faces, area}], extraordinary_points, sharp_edges, "
              "connection_lines, dropped_connection_lines, auxiliary_vertices, graph_edges, mst_edges, nf_edges, "
              "clipping_edges: {priority_1 .. priority_7}, height_field_splits, joins, base_direction}")
      .param_float("angle", 50.0, 0, 179.9, "deg", "an edge is sharp when its faces' normals differ by more (theta)")
      .param_float("min_normal_dot", 0.05, -1, 0.99, "",
                   "a patch is a height field along d when every face normal n has n.d above this; patches that "
                   "are not are halved until they are")
      .param_bool("join", true, "join neighbouring patches sharing a whole side without a sharp edge")
      .param_float("join_min_normal_dot", 0.5, -1, 1, "",
                   "... while every face normal n of the union has n.d above this (0.5: within 60 degrees)");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    SegmentOptions o;
    o.sharp_angle_deg = ctx.number("angle");
    o.min_normal_dot = ctx.number("min_normal_dot");
    o.join = ctx.flag("join");
    o.join_min_normal_dot = ctx.number("join_min_normal_dot");
    SegmentStats stats;
    Segments s;
    try {
      s = segment_shf(*mesh, o, &stats, nullptr, [&](double f, const std::string& m) { ctx.progress(f, m); });
    } catch (const std::exception& e) {
      throw NodeError(std::string("mesh.segment: ") + e.what());
    }
    if (ctx.has_input("base")) {
      const auto& b = ctx.input<Report>("base")->data;
      if (b.contains("base_direction") && b["base_direction"].is_array() && b["base_direction"].size() == 3)
        s.base_direction = Eigen::Vector3d(b["base_direction"][0].get<double>(), b["base_direction"][1].get<double>(),
                                           b["base_direction"][2].get<double>());
    }
    const FaceGeometry g = face_geometry(s.mesh);
    nlohmann::json patches = nlohmann::json::array();
    for (const auto& p : s.patches) {
      double area = 0;
      for (auto f : p.faces) area += g.area[f];
      patches.push_back({{"direction", {p.direction.x(), p.direction.y(), p.direction.z()}},
                         {"min_normal_dot", p.min_normal_dot},
                         {"rows", p.rows},
                         {"cols", p.cols},
                         {"faces", p.faces.size()},
                         {"area", area}});
    }
    nlohmann::json clipping;
    for (int k = 1; k <= 7; ++k) clipping["priority_" + std::to_string(k)] = stats.clipping_by_priority[k];
    Report report;
    report.data = {{"patches", std::move(patches)},
                   {"extraordinary_points", stats.extraordinary_points},
                   {"sharp_edges", stats.sharp_edges},
                   {"connection_lines", stats.connection_lines},
                   {"dropped_connection_lines", stats.dropped_connection_lines},
                   {"auxiliary_vertices", stats.auxiliary_vertices},
                   {"graph_edges", stats.graph_edges},
                   {"mst_edges", stats.mst_edges},
                   {"nf_edges", stats.nf_edges},
                   {"clipping_edges", std::move(clipping)},
                   {"height_field_splits", stats.height_field_splits},
                   {"joins", stats.joins},
                   {"base_direction", {s.base_direction.x(), s.base_direction.y(), s.base_direction.z()}}};
    ctx.set("report", std::move(report));
    ctx.set("segments", std::move(s));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
