#include "engine/node.h"
#include "nodes/io/mm_units.h"
#include "nodes/io/read_input.h"
#include "nodes/io/read_mesh.h"
#include "nodes/io/read_support.h"
#include "nodes/mesh/topology_report.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::io_nodes {

NodeDecl make_read_mesh_node() {
  NodeDecl d;
  d.type = "io.read_mesh";
  d.version = 1;
  d.description = "reads a polygon mesh from PLY, OFF, OBJ or STL (ascii or binary; STL corners welded) and reports its topology";
  d.input("file", "File", "the mesh file; the format is chosen by its extension")
      .output("mesh", "Mesh", "vertices and faces as the file has them (triangles, quads, any polygon); vertex normals, face labels and feature edges when a PLY or NOFF file has them")
      .output("report", "Report",
              "{file, vertices, faces, edges, triangles, quads, other_polygons, components, boundary_loops, genus "
              "(-1 with non-manifold edges), non_manifold_edges, degenerate_faces, isolated_vertices, closed; STL: "
              "corners_welded}")
      .param_float("scale", 1.0, 1e-9, 1e9, "", "multiplies every coordinate, e.g. 1000 for a file in metres");
  d.run = [](NodeContext& ctx) {
    std::string path;
    Mesh mesh = io::read_input(ctx, read_mesh, path);
    check_units(ctx, path, mesh.vertices, false, "mesh");
    Report r;
    r.data = topology_report(mesh);
    r.data["file"] = path;
    if (io::lower_extension(path) == ".stl") r.data["corners_welded"] = mesh.face_vertices.size() - mesh.num_vertices();
    ctx.set("report", std::move(r));
    ctx.set("mesh", std::move(mesh));
  };
  return d;
}

}  // namespace scallop::io_nodes
