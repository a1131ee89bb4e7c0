#include "nodes/mesh/keep_faces.h"

#include <cstdint>

#include "nodes/mesh/mesh_topology.h"

namespace scallop {

Mesh keep_faces(const Mesh& mesh, const std::vector<bool>& keep, std::vector<std::uint32_t>* new_index) {
  const std::size_t F = mesh.num_faces();
  std::vector<bool> used(mesh.num_vertices(), false);
  for (std::size_t f = 0; f < F; ++f)
    if (keep[f])
      for (std::size_t c = 0; c < mesh.face_size(f); ++c) used[mesh.face(f)[c]] = true;
  std::vector<std::uint32_t> index(mesh.num_vertices(), UINT32_MAX);
  Mesh out;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    if (!used[v]) continue;
    index[v] = static_cast<std::uint32_t>(out.vertices.size());
    out.vertices.push_back(mesh.vertices[v]);
    if (mesh.has_normals()) out.normals.push_back(mesh.normals[v]);
  }
  for (std::size_t f = 0; f < F; ++f) {
    if (!keep[f]) continue;
    const std::size_t first = out.face_vertices.size();
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) out.face_vertices.push_back(index[mesh.face(f)[c]]);
    out.face_start.push_back(static_cast<std::uint32_t>(first + mesh.face_size(f)));
    if (mesh.has_labels()) out.face_label.push_back(mesh.face_label[f]);
  }
  if (!mesh.feature_edges.empty()) {
    const MeshEdges edges = mesh_edges(out);
    // The renumbering keeps the order of the vertices, so a < b and the sorting stay.
    for (const auto& [a, b] : mesh.feature_edges)
      if (index[a] != UINT32_MAX && index[b] != UINT32_MAX && edges.find(index[a], index[b]))
        out.feature_edges.push_back({index[a], index[b]});
  }
  if (new_index) *new_index = std::move(index);
  return out;
}

}  // namespace scallop
