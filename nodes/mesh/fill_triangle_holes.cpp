#include "nodes/mesh/fill_triangle_holes.h"

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <set>
#include <tuple>

#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// A step of a strip: the face crossed and the edges it is entered and left by (kNone at the
// strip's first triangle's entry).
struct Step {
  std::uint32_t face, in, out;
};

// Slot (corner index) of edge e in face f.
std::size_t slot_of(const Mesh& mesh, const MeshEdges& edges, std::uint32_t f, std::uint32_t e) {
  for (std::size_t k = 0; k < mesh.face_size(f); ++k)
    if (edges.face_edge[mesh.face_start[f] + k] == e) return k;
  return kNone;
}

// The cheapest strip from triangle `start` to another triangle, or to a border edge when
// `to_border`: Dijkstra over faces (each face once), a quad crossed straight costing 1, one
// crossed turning 3. Empty when none is reachable.
std::vector<Step> find_strip(const Mesh& mesh, const MeshEdges& edges, std::uint32_t start, bool to_border) {
  const auto F = static_cast<std::uint32_t>(mesh.num_faces());
  const std::uint32_t border = F;  // a virtual face beyond every border edge
  std::vector<bool> settled(F + 1, false);
  std::vector<std::uint32_t> entry(F + 1, kNone), from(F + 1, kNone);
  using Item = std::tuple<int, std::uint32_t, std::uint32_t, std::uint32_t>;  // cost, face, via edge, from
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  queue.push({0, start, kNone, kNone});
  std::uint32_t end = kNone;
  while (!queue.empty()) {
    const auto [cost, f, via, prev] = queue.top();
    queue.pop();
    if (settled[f]) continue;
    settled[f] = true, entry[f] = via, from[f] = prev;
    if (f == border || (f != start && mesh.face_size(f) == 3)) {
      end = f;
      break;
    }
    const std::size_t n = mesh.face_size(f), in = via == kNone ? kNone : slot_of(mesh, edges, f, via);
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t e = edges.face_edge[mesh.face_start[f] + k];
      if (e == via) continue;
      const int step = in == kNone || (k + n - in) % n == n / 2 ? 1 : 3;
      if (edges.is_boundary(e)) {
        if (to_border) queue.push({cost + step, border, e, f});
        continue;
      }
      const std::uint32_t g = edges.faces(e)[0] == f ? edges.faces(e)[1] : edges.faces(e)[0];
      if (!settled[g]) queue.push({cost + step, g, e, f});
    }
  }
  std::vector<Step> strip;
  if (end == kNone) return strip;
  std::uint32_t f = end, out = kNone;
  if (end == border) out = entry[border], f = from[border];  // the last quad leaves by a border edge
  for (; f != kNone; f = from[f]) {
    strip.push_back({f, entry[f], out});
    out = entry[f];
  }
  std::reverse(strip.begin(), strip.end());
  return strip;
}

// Splits the strip's faces: each crossed edge gains its midpoint as a vertex.
std::size_t split_strip(Mesh& mesh, const MeshEdges& edges, const std::vector<Step>& strip) {
  std::map<std::uint32_t, std::uint32_t> midpoint;  // edge -> new vertex
  auto add_midpoint = [&](std::uint32_t e) {
    if (e == kNone || midpoint.count(e)) return;
    midpoint[e] = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.push_back(0.5 * (mesh.vertices[edges.edges[e][0]] + mesh.vertices[edges.edges[e][1]]));
  };
  for (const Step& s : strip) add_midpoint(s.in), add_midpoint(s.out);
  std::vector<bool> on_strip(mesh.num_faces(), false);
  for (const Step& s : strip) on_strip[s.face] = true;

  Mesh out;
  out.vertices = mesh.vertices;
  std::size_t split = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::vector<std::uint32_t> corners(mesh.face(f), mesh.face(f) + mesh.face_size(f));
    if (!on_strip[f]) {
      out.add_face_range(corners);
      continue;
    }
    std::vector<std::uint32_t> c;
    std::vector<std::size_t> mids;  // positions of the midpoints in c
    for (std::size_t k = 0; k < corners.size(); ++k) {
      c.push_back(corners[k]);
      if (auto it = midpoint.find(edges.face_edge[mesh.face_start[f] + k]); it != midpoint.end()) {
        mids.push_back(c.size());
        c.push_back(it->second);
      }
    }
    if (c.size() == 4) {  // a triangle with one midpoint
      out.add_face_range(c);
      continue;
    }
    // A quad with two midpoints: split between them when they face each other, else through the
    // corner between their edges.
    const std::size_t i = mids[0], j = mids[1];
    const std::size_t s = j - i == 3 ? i : (j - i == 2 ? i + 1 : (j + 1) % 6);
    auto at = [&](std::size_t k) { return c[(s + k) % 6]; };
    out.add_face({at(0), at(1), at(2), at(3)});
    out.add_face({at(3), at(4), at(5), at(0)});
    ++split;
  }
  mesh = std::move(out);
  return split;
}

}  // namespace

TriangleHoleFill fill_triangle_holes(Mesh& mesh, const std::vector<std::vector<std::uint32_t>>& holes) {
  TriangleHoleFill r;
  // boundary_loops runs a loop the way its one face runs each edge: the filling face runs it back.
  for (const auto& h : holes) mesh.add_face({h[0], h[2], h[1]}), ++r.holes;
  std::set<std::array<std::uint32_t, 3>> stuck;  // triangles no strip reaches, by their corners
  while (true) {
    const MeshEdges edges = mesh_edges(mesh);
    bool border = false;
    for (std::size_t e = 0; e < edges.size() && !border; ++e) border = edges.is_boundary(e);
    std::uint32_t start = kNone;
    for (std::uint32_t f = 0; f < mesh.num_faces() && start == kNone; ++f)
      if (mesh.face_size(f) == 3 && !stuck.count({mesh.face(f)[0], mesh.face(f)[1], mesh.face(f)[2]})) start = f;
    if (start == kNone) break;
    const std::vector<Step> strip = find_strip(mesh, edges, start, border);
    if (strip.empty()) {
      stuck.insert({mesh.face(start)[0], mesh.face(start)[1], mesh.face(start)[2]});
      ++r.left;
      continue;
    }
    r.quads_split += split_strip(mesh, edges, strip);
  }
  return r;
}

}  // namespace scallop
