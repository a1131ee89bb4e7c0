// Meshes with known answers for the mesh and mesh-file tests: a quad cube, a tetrahedron, a
// triangulated cube, an icosphere, noise along the vertex normals.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "nodes/mesh/face_geometry.h"
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

// Outward unit normal of the cube's side s: 0..2 the low sides x = 0, y = 0, z = 0, 3..5 the
// high sides x = 1, y = 1, z = 1.
inline Eigen::Vector3d cube_side_normal(int s) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[s % 3] = s < 3 ? -1 : 1;
  return n;
}

// The cube [0, edge]^3, each side an n x n grid of squares cut into two triangles along
// alternating diagonals, vertices shared along the cube's edges, faces outward; face_label is
// the side (cube_side_normal). 12 n^2 triangles, 6 n^2 + 2 vertices.
inline Mesh cube_mesh(int n, double edge = 1.0) {
  Mesh m;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](std::array<int, 3> p) {
    auto [it, added] = index.try_emplace(p, static_cast<std::uint32_t>(m.vertices.size()));
    if (added) m.vertices.push_back(Eigen::Vector3d(p[0], p[1], p[2]) * (edge / n));
    return it->second;
  };
  for (int s = 0; s < 6; ++s) {
    const int a = s % 3, b = (a + 1) % 3, c = (a + 2) % 3;
    const bool high = s >= 3;
    for (int u = 0; u < n; ++u)
      for (int v = 0; v < n; ++v) {
        std::array<std::uint32_t, 4> q;
        const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; ++k) {
          std::array<int, 3> p;
          p[a] = high ? n : 0;
          p[b] = u + du[k];
          p[c] = v + dv[k];
          q[k] = vertex(p);
        }
        // (b, c) counter-clockwise is outward on the high side (e_b x e_c = e_a).
        if (!high) std::swap(q[1], q[3]);
        if ((u + v) % 2 == 0) {
          m.add_face({q[0], q[1], q[2]});
          m.add_face({q[0], q[2], q[3]});
        } else {
          m.add_face({q[0], q[1], q[3]});
          m.add_face({q[1], q[2], q[3]});
        }
        m.face_label.push_back(s);
        m.face_label.push_back(s);
      }
  }
  return m;
}

// The cube [0, 4]^3 (cube_mesh(4, 4)) with the middle vertex of its top pulled down to
// (2, 2, -1): its 8 faces (into `spike`) run through the cube and out of its bottom, a closed,
// consistently oriented mesh that crosses itself.
inline Mesh spiked_cube(std::set<std::size_t>& spike) {
  Mesh m = cube_mesh(4, 4.0);
  const auto top = std::find(m.vertices.begin(), m.vertices.end(), Eigen::Vector3d(2, 2, 4)) - m.vertices.begin();
  m.vertices[top] = Eigen::Vector3d(2, 2, -1);
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    if (std::count(m.face(f), m.face(f) + m.face_size(f), std::uint32_t(top))) spike.insert(f);
  return m;
}

// The icosahedron's faces split `levels` times into four, projected on the sphere of `radius`
// about the origin: 20 * 4^levels triangles, outward.
inline Mesh icosphere(int levels, double radius = 1.0) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Mesh m;
  for (auto p : std::vector<Eigen::Vector3d>{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}})
    m.vertices.push_back(p.normalized());
  std::vector<std::array<std::uint32_t, 3>> faces = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto middle = [&](std::uint32_t a, std::uint32_t b) {
      auto [it, added] = mid.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<std::uint32_t>(m.vertices.size()));
      if (added) m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return it->second;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (auto [a, b, c] : faces) {
      const auto ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(next);
  }
  for (auto& v : m.vertices) v *= radius;
  for (auto [a, b, c] : faces) m.add_face({a, b, c});
  return m;
}

// Moves every vertex along its area-weighted vertex normal by Gaussian noise of standard
// deviation sigma (a fixed generator and seed: the same mesh every run).
inline Mesh add_normal_noise(Mesh m, double sigma, unsigned seed) {
  std::vector<Eigen::Vector3d> n(m.vertices.size(), Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const auto* c = m.face(f);
    const Eigen::Vector3d area = (m.vertices[c[1]] - m.vertices[c[0]]).cross(m.vertices[c[2]] - m.vertices[c[0]]);
    for (int k = 0; k < 3; ++k) n[c[k]] += area;
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) m.vertices[v] += noise(rng) * n[v].normalized();
  return m;
}

// Area-weighted mean angle (degrees) between the faces of a (denoised) cube_mesh of edge 1 and
// their side's true normal (face_label: the side), over faces whose centroid lies farther than
// `margin` from the cube's edges.
inline double cube_normal_error_deg(const Mesh& m, double margin) {
  const FaceGeometry g = face_geometry(m);
  double sum = 0, area = 0;
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const int s = m.face_label[f], a = s % 3;
    double to_edge = 1e9;
    for (int c = 0; c < 3; ++c)
      if (c != a) to_edge = std::min({to_edge, g.centroid[f][c], 1 - g.centroid[f][c]});
    if (to_edge <= margin) continue;
    sum += g.area[f] * angle_deg(g.normal[f], cube_side_normal(s));
    area += g.area[f];
  }
  return sum / area;
}

// The box [0, size.x] x [0, size.y] x [0, size.z] as quads: each side a grid of n[b] x n[c]
// squares along its two axes b, c, vertices shared along the box's edges, faces counter-
// clockwise seen from outside; face_label is the side (cube_side_normal).
inline Mesh quad_box(std::array<int, 3> n, Eigen::Vector3d size) {
  Mesh m;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](std::array<int, 3> p) {
    auto [it, added] = index.try_emplace(p, static_cast<std::uint32_t>(m.vertices.size()));
    if (added)
      m.vertices.push_back(Eigen::Vector3d(p[0] * size.x() / n[0], p[1] * size.y() / n[1], p[2] * size.z() / n[2]));
    return it->second;
  };
  for (int s = 0; s < 6; ++s) {
    const int a = s % 3, b = (a + 1) % 3, c = (a + 2) % 3;
    const bool high = s >= 3;
    for (int u = 0; u < n[b]; ++u)
      for (int v = 0; v < n[c]; ++v) {
        std::array<std::uint32_t, 4> q;
        const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; ++k) {
          std::array<int, 3> p;
          p[a] = high ? n[a] : 0;
          p[b] = u + du[k];
          p[c] = v + dv[k];
          q[k] = vertex(p);
        }
        if (!high) std::swap(q[1], q[3]);
        m.add_face({q[0], q[1], q[2], q[3]});
        m.face_label.push_back(s);
      }
  }
  return m;
}

// A flat open grid of nx by ny unit squares in the plane z = 0, faces counter-clockwise seen
// from +z, vertex (i, j) at index j * (nx + 1) + i; `height` lifts each vertex to z = height(x, y).
template <class Height>
inline Mesh quad_sheet(int nx, int ny, double step, Height height) {
  Mesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.vertices.push_back({i * step, j * step, height(i * step, j * step)});
  auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.add_face({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  return m;
}

// A closed cylinder of radius 10 and height 15 about the z axis: a quad box pressed onto it (the
// square's rings onto circles), so its eight corners stay extraordinary points on the caps' rims.
inline Mesh capped_cylinder(int n) {
  Mesh m = test::quad_box({n, n, n}, {2, 2, 15});
  for (auto& v : m.vertices) {
    const Eigen::Vector2d xy(v.x() - 1, v.y() - 1);
    const double r = xy.lpNorm<Eigen::Infinity>();
    const Eigen::Vector2d d = r > 0 ? Eigen::Vector2d(xy * (r / xy.norm()) * 10) : Eigen::Vector2d::Zero();
    v = Eigen::Vector3d(d.x(), d.y(), v.z());
  }
  return m;
}

}  // namespace scallop::test
