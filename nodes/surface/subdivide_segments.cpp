#include "nodes/surface/subdivide_segments.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <utility>

#include "nodes/mesh/mesh_topology.h"

namespace scallop {

Segments subdivide_segments(const Segments& seg, const Mesh& part, SnapReport* snap) {
  if (part.num_faces() == 0) throw std::invalid_argument("subdivide_segments: the part has no faces");
  const Mesh& m = seg.mesh;
  Segments out;
  out.base_direction = seg.base_direction;
  Mesh& fine = out.mesh;
  fine.vertices = m.vertices;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_point;
  auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    auto [it, added] = edge_point.try_emplace({key.first, key.second}, std::uint32_t(fine.vertices.size()));
    if (added) fine.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
    return it->second;
  };
  std::vector<std::uint32_t> face_point(m.num_faces()), first_face(m.num_faces());
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const std::uint32_t* c = m.face(f);
    const std::size_t n = m.face_size(f);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < n; ++k) centre += m.vertices[c[k]] / double(n);
    face_point[f] = std::uint32_t(fine.vertices.size());
    fine.vertices.push_back(centre);
    first_face[f] = std::uint32_t(fine.num_faces());
    // The quad at corner k: the corner, the next edge's midpoint, the centre, the previous edge's
    // midpoint (the face's own turning sense).
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t next = midpoint(c[k], c[(k + 1) % n]), previous = midpoint(c[(k + n - 1) % n], c[k]);
      fine.add_face({c[k], next, face_point[f], previous});
      if (m.has_labels()) fine.face_label.push_back(m.face_label[f]);
    }
  }
  auto halves = [&](const std::vector<std::array<std::uint32_t, 2>>& edges) {
    std::vector<std::array<std::uint32_t, 2>> cut;
    for (const auto& [a, b] : edges) {
      const std::uint32_t e = midpoint(a, b);
      cut.push_back({std::min(a, e), std::max(a, e)});
      cut.push_back({std::min(e, b), std::max(e, b)});
    }
    return cut;
  };
  fine.feature_edges = halves(m.feature_edges);
  out.clipping_edges = halves(seg.clipping_edges);
  const SnapReport r = snap_to_reference(fine, part, part.feature_edges, mean_edge_length(fine));
  if (snap) *snap = r;

  for (const SegmentPatch& p : seg.patches) {
    SegmentPatch q;
    q.direction = p.direction;
    q.min_normal_dot = p.min_normal_dot;
    q.rows = 2 * p.rows - 1, q.cols = 2 * p.cols - 1;
    q.grid.assign(std::size_t(q.rows) * q.cols, 0);
    q.faces.assign(std::size_t(q.rows - 1) * (q.cols - 1), 0);
    auto set = [&](std::uint32_t i, std::uint32_t j, std::uint32_t v) { q.grid[std::size_t(i) * q.cols + j] = v; };
    for (std::uint32_t i = 0; i < p.rows; ++i)
      for (std::uint32_t j = 0; j < p.cols; ++j) {
        set(2 * i, 2 * j, p.at(i, j));
        if (j + 1 < p.cols) set(2 * i, 2 * j + 1, midpoint(p.at(i, j), p.at(i, j + 1)));
        if (i + 1 < p.rows) set(2 * i + 1, 2 * j, midpoint(p.at(i, j), p.at(i + 1, j)));
      }
    for (std::uint32_t i = 0; i + 1 < p.rows; ++i)
      for (std::uint32_t j = 0; j + 1 < p.cols; ++j) {
        const std::uint32_t f = p.faces[std::size_t(i) * (p.cols - 1) + j];
        set(2 * i + 1, 2 * j + 1, face_point[f]);
        // Sub-cell (2i + a, 2j + b) holds the old corner (i + a, j + b): the quad at that corner.
        for (std::uint32_t a = 0; a < 2; ++a)
          for (std::uint32_t b = 0; b < 2; ++b) {
            const std::uint32_t corner = p.at(i + a, j + b);
            const std::uint32_t* c = m.face(f);
            const auto k = std::uint32_t(std::find(c, c + m.face_size(f), corner) - c);
            if (k == m.face_size(f))
              throw std::invalid_argument("subdivide_segments: a patch's grid does not match its faces");
            q.faces[std::size_t(2 * i + a) * (q.cols - 1) + 2 * j + b] = first_face[f] + k;
          }
      }
    out.patches.push_back(std::move(q));
  }
  return out;
}

}  // namespace scallop
