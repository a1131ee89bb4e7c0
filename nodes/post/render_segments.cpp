#include "nodes/post/render_segments.h"

#include <Eigen/Geometry>
#include <set>

#include "nodes/mesh/mesh_topology.h"

namespace scallop {

std::vector<MeshOverlay> segment_overlays(const Segments& s) {
  std::vector<MeshOverlay> out;
  const Mesh& m = s.mesh;
  for (const auto& e : s.clipping_edges) out.push_back({{m.vertices[e[0]], m.vertices[e[1]]}, {0.15, 0.15, 0.18}, 2, false});
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& v : m.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const double length = m.vertices.empty() ? 0 : 0.08 * (hi - lo).norm();
  for (const auto& p : s.patches) {
    if (p.grid.empty()) continue;
    const Eigen::Vector3d from = m.vertices[p.at(p.rows / 2, p.cols / 2)];
    const Eigen::Vector3d tip = from + length * p.direction;
    const Eigen::Vector3d side = p.direction.unitOrthogonal() * (0.25 * length);
    const Eigen::Vector3d back = tip - 0.25 * length * p.direction;
    // One polyline, so that the head is drawn exactly when the shaft is.
    out.push_back({{from, tip, back + side, tip, back - side}, {0, 0, 0}, 2, true});
  }
  return out;
}

Mesh patch_colour_mesh(const Segments& s) {
  Mesh m = s.mesh;
  const std::size_t n = s.patches.size();
  std::vector<std::set<std::size_t>> next_to(n);
  const MeshEdges edges = mesh_edges(m);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges.faces_on(e) != 2) continue;
    const int a = m.face_label[edges.faces(e)[0]], b = m.face_label[edges.faces(e)[1]];
    if (a >= 0 && b >= 0 && a != b) next_to[a].insert(b), next_to[b].insert(a);
  }
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return s.patches[a].faces.size() > s.patches[b].faces.size(); });
  std::vector<int> slot(n, -1);
  for (auto p : order) {
    std::set<int> taken;
    for (auto q : next_to[p]) taken.insert(slot[q]);
    int c = 0;
    while (taken.count(c)) ++c;
    slot[p] = c;
  }
  for (auto& l : m.face_label)
    if (l >= 0) l = slot[l];
  return m;
}

}  // namespace scallop
