// Connectivity of a polygon mesh: its edges with the faces on them, components, boundary loops,
// genus, and what is not a manifold. The one home of mesh connectivity for the mesh nodes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// The undirected edges of a mesh and the faces on each.
//   edges       #E vertex pairs (a < b), sorted.
//   edge_faces  faces on edge e: edge_face[edge_face_start[e] .. edge_face_start[e+1]).
//   face_edge   for corner c of face f, the edge from that corner to the next:
//               face_edge[mesh.face_start[f] + c].
struct MeshEdges {
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<std::uint32_t> edge_face_start{0};
  std::vector<std::uint32_t> edge_face;
  std::vector<std::uint32_t> face_edge;

  std::size_t size() const { return edges.size(); }
  std::size_t faces_on(std::size_t e) const { return edge_face_start[e + 1] - edge_face_start[e]; }
  const std::uint32_t* faces(std::size_t e) const { return edge_face.data() + edge_face_start[e]; }
  bool is_boundary(std::size_t e) const { return faces_on(e) == 1; }
  bool is_manifold(std::size_t e) const { return faces_on(e) <= 2; }
  // The edge joining a and b (either order), if there is one.
  std::optional<std::uint32_t> find(std::uint32_t a, std::uint32_t b) const;
};

MeshEdges mesh_edges(const Mesh& mesh);

// Component id (0, 1, ...) of every face, faces joined through shared edges.
std::vector<int> face_components(const Mesh& mesh, const MeshEdges& edges);

// Per component of `component` (face_components' ids), whether it is closed: each of its edges on
// exactly two faces.
std::vector<bool> closed_components(const MeshEdges& edges, const std::vector<int>& component);

// Boundary loops: each a closed chain of vertices along edges with one face, in the direction of
// that face's corners. Where a vertex has several boundary edges out (non-manifold), loops
// are cut at the first free one.
std::vector<std::vector<std::uint32_t>> boundary_loops(const Mesh& mesh, const MeshEdges& edges);

// The faces around each vertex: faces of vertex v are
// face[start[v] .. start[v+1]), in increasing order, each once (also when it has v twice).
struct VertexFaces {
  std::vector<std::uint32_t> start{0};
  std::vector<std::uint32_t> face;
  std::size_t count(std::size_t v) const { return start[v + 1] - start[v]; }
  const std::uint32_t* faces(std::size_t v) const { return face.data() + start[v]; }
};

VertexFaces vertex_faces(const Mesh& mesh);

// Newell's area vector of face f: its direction is the face normal, its length twice its area.
Eigen::Vector3d face_area_vector(const Mesh& mesh, std::size_t f);

// What io.read_mesh and mesh.repair report.
struct MeshTopology {
  std::size_t vertices = 0, faces = 0, edges = 0;
  int components = 0;
  int boundary_loops = 0;
  // Sum over components of g in V - E + F = 2 - 2g - b; -1 when the mesh has non-manifold
  // edges (then genus has no meaning).
  int genus = 0;
  std::size_t non_manifold_edges = 0;  // edges with 3 or more faces
  std::size_t degenerate_faces = 0;    // a repeated corner, or no area (relative to the size)
  std::size_t isolated_vertices = 0;   // on no face
};

MeshTopology mesh_topology(const Mesh& mesh, const MeshEdges& edges);

// The mean length of the mesh's edges, each counted once (0 without edges).
double mean_edge_length(const Mesh& mesh);

}  // namespace scallop
