#include "nodes/mesh/topology_report.h"

#include "nodes/mesh/mesh_topology.h"

namespace scallop {

nlohmann::json topology_report(const Mesh& mesh) {
  const MeshTopology t = mesh_topology(mesh, mesh_edges(mesh));
  std::size_t triangles = 0, quads = 0, other = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::size_t n = mesh.face_size(f);
    (n == 3 ? triangles : n == 4 ? quads : other) += 1;
  }
  return {{"vertices", t.vertices},
          {"faces", t.faces},
          {"edges", t.edges},
          {"triangles", triangles},
          {"quads", quads},
          {"other_polygons", other},
          {"components", t.components},
          {"boundary_loops", t.boundary_loops},
          {"genus", t.genus},
          {"non_manifold_edges", t.non_manifold_edges},
          {"degenerate_faces", t.degenerate_faces},
          {"isolated_vertices", t.isolated_vertices},
          {"closed", t.boundary_loops == 0 && t.non_manifold_edges == 0 && t.faces > 0}};
}

}  // namespace scallop
