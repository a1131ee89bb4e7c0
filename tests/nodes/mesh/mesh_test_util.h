// Small closed meshes with known answers, for the mesh and mesh-file tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop::test {

// The unit cube [0,1]^3 as six quads, corners counter-clockwise seen from outside. Vertex i is
// (i & 1, (i >> 1) & 1, (i >> 2) & 1); face 0 is the bottom (z = 0), 1 the top.
inline Mesh unit_cube() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(Eigen::Vector3d(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  m.add_face({0, 2, 3, 1});
  m.add_face({4, 5, 7, 6});
  m.add_face({0, 1, 5, 4});
  m.add_face({2, 6, 7, 3});
  m.add_face({0, 4, 6, 2});
  m.add_face({1, 3, 7, 5});
  return m;
}

// The tetrahedron on the origin and the three unit points, four triangles facing outward.
inline Mesh tetrahedron() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.add_face({0, 2, 1});
  m.add_face({0, 1, 3});
  m.add_face({0, 3, 2});
  m.add_face({1, 2, 3});
  return m;
}

// The corners of face f.
inline std::vector<std::uint32_t> corners(const Mesh& m, std::size_t f) {
  return std::vector<std::uint32_t>(m.face(f), m.face(f) + m.face_size(f));
}

}  // namespace scallop::test
