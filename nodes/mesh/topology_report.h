// A mesh's topology as report fields: what io.read_mesh and mesh.repair say about the mesh they
// give.
#pragma once

#include <nlohmann/json.hpp>

#include "nodes/types/mesh.h"

namespace scallop {

// {vertices, faces, edges, triangles, quads, other_polygons (5 corners or more), components,
//  boundary_loops, genus (-1 with non-manifold edges), non_manifold_edges, degenerate_faces,
//  isolated_vertices, closed (no boundary loop, no non-manifold edge)}, from mesh_topology.
nlohmann::json topology_report(const Mesh& mesh);

}  // namespace scallop
