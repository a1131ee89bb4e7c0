#include "nodes/types/segments.h"

#include <stdexcept>

#include "nodes/types/ply_writer.h"

namespace scallop {

void Segments::serialize(std::ostream& out) const {
  mesh.serialize(out);
  bin::write_u64(out, patches.size());
  for (const auto& p : patches) {
    bin::write_vector(out, std::vector<Eigen::Vector3d>{p.direction});
    bin::write_f64(out, p.min_normal_dot);
    bin::write_vector(out, p.faces);
    bin::write_u64(out, p.rows);
    bin::write_u64(out, p.cols);
    bin::write_vector(out, p.grid);
  }
  bin::write_vector(out, clipping_edges);
  bin::write_vector(out, std::vector<Eigen::Vector3d>{base_direction});
}

ValuePtr Segments::deserialize(std::istream& in) {
  auto s = std::make_shared<Segments>();
  s->mesh = *std::static_pointer_cast<const Mesh>(Mesh::deserialize(in));
  const std::uint64_t n = bin::read_u64(in);
  if (n > s->mesh.num_faces()) throw std::runtime_error("corrupt segments: patch count");
  s->patches.resize(n);
  for (auto& p : s->patches) {
    auto d = bin::read_vector<Eigen::Vector3d>(in);
    if (d.size() != 1) throw std::runtime_error("corrupt segments: direction");
    p.direction = d[0];
    p.min_normal_dot = bin::read_f64(in);
    p.faces = bin::read_vector<std::uint32_t>(in);
    const std::uint64_t rows = bin::read_u64(in), cols = bin::read_u64(in);
    p.grid = bin::read_vector<std::uint32_t>(in);
    if (rows > (1u << 30) || cols > (1u << 30) || rows * cols != p.grid.size())
      throw std::runtime_error("corrupt segments: grid size");
    p.rows = static_cast<std::uint32_t>(rows);
    p.cols = static_cast<std::uint32_t>(cols);
    for (auto f : p.faces)
      if (f >= s->mesh.num_faces()) throw std::runtime_error("corrupt segments: face index");
    for (auto v : p.grid)
      if (v >= s->mesh.num_vertices()) throw std::runtime_error("corrupt segments: vertex index");
  }
  s->clipping_edges = bin::read_vector<std::array<std::uint32_t, 2>>(in);
  for (const auto& e : s->clipping_edges)
    if (e[0] >= s->mesh.num_vertices() || e[1] >= s->mesh.num_vertices())
      throw std::runtime_error("corrupt segments: edge index");
  auto b = bin::read_vector<Eigen::Vector3d>(in);
  if (b.size() != 1) throw std::runtime_error("corrupt segments: base direction");
  s->base_direction = b[0];
  return s;
}

void Segments::write_file(const std::string& path) const {
  Mesh labelled = mesh;
  labelled.feature_edges = clipping_edges;
  write_mesh_ply(path, labelled);
}

}  // namespace scallop
