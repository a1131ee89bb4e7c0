#include "nodes/types/mesh.h"

#include "nodes/types/ply_writer.h"

namespace scallop {

void Mesh::serialize(std::ostream& out) const {
  bin::write_vector(out, vertices);
  bin::write_vector(out, face_start);
  bin::write_vector(out, face_vertices);
  bin::write_vector(out, normals);
  bin::write_vector(out, face_label);
  bin::write_vector(out, feature_edges);
}

ValuePtr Mesh::deserialize(std::istream& in) {
  auto m = std::make_shared<Mesh>();
  m->vertices = bin::read_vector<Eigen::Vector3d>(in);
  m->face_start = bin::read_vector<std::uint32_t>(in);
  m->face_vertices = bin::read_vector<std::uint32_t>(in);
  m->normals = bin::read_vector<Eigen::Vector3d>(in);
  m->face_label = bin::read_vector<std::int32_t>(in);
  m->feature_edges = bin::read_vector<std::array<std::uint32_t, 2>>(in);
  // A cache entry is checksummed, but its shape is checked too: nothing indexes past an array.
  if (m->face_start.empty() || m->face_start.front() != 0 || m->face_start.back() != m->face_vertices.size())
    throw std::runtime_error("corrupt mesh: face offsets");
  for (std::size_t f = 0; f + 1 < m->face_start.size(); ++f)
    if (m->face_start[f + 1] < m->face_start[f] + 3) throw std::runtime_error("corrupt mesh: face size");
  for (auto v : m->face_vertices)
    if (v >= m->vertices.size()) throw std::runtime_error("corrupt mesh: vertex index");
  for (const auto& e : m->feature_edges)
    if (e[0] >= m->vertices.size() || e[1] >= m->vertices.size()) throw std::runtime_error("corrupt mesh: edge index");
  return m;
}

void Mesh::write_file(const std::string& path) const { write_mesh_ply(path, *this); }

}  // namespace scallop
