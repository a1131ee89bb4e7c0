#include "nodes/mesh/mesh_topology.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>
#include <tuple>

namespace scallop {

std::optional<std::uint32_t> MeshEdges::find(std::uint32_t a, std::uint32_t b) const {
  const std::array<std::uint32_t, 2> key{std::min(a, b), std::max(a, b)};
  auto it = std::lower_bound(edges.begin(), edges.end(), key);
  if (it == edges.end() || *it != key) return std::nullopt;
  return static_cast<std::uint32_t>(it - edges.begin());
}

MeshEdges mesh_edges(const Mesh& mesh) {
  // One record per face corner (edge key, face, corner slot), sorted so equal edges are adjacent.
  struct Corner {
    std::uint32_t a, b, face, slot;
  };
  std::vector<Corner> corners;
  corners.reserve(mesh.face_vertices.size());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::size_t n = mesh.face_size(f);
    for (std::size_t c = 0; c < n; ++c) {
      std::uint32_t u = mesh.face(f)[c], v = mesh.face(f)[(c + 1) % n];
      corners.push_back({std::min(u, v), std::max(u, v), static_cast<std::uint32_t>(f),
                         static_cast<std::uint32_t>(mesh.face_start[f] + c)});
    }
  }
  std::sort(corners.begin(), corners.end(), [](const Corner& x, const Corner& y) {
    return std::tie(x.a, x.b, x.face) < std::tie(y.a, y.b, y.face);
  });
  MeshEdges out;
  out.face_edge.assign(mesh.face_vertices.size(), 0);
  for (std::size_t i = 0; i < corners.size();) {
    std::size_t j = i;
    const auto e = static_cast<std::uint32_t>(out.edges.size());
    out.edges.push_back({corners[i].a, corners[i].b});
    for (; j < corners.size() && corners[j].a == corners[i].a && corners[j].b == corners[i].b; ++j) {
      // A face that runs along the same edge twice counts once on it.
      if (j == i || corners[j].face != corners[j - 1].face) out.edge_face.push_back(corners[j].face);
      out.face_edge[corners[j].slot] = e;
    }
    out.edge_face_start.push_back(static_cast<std::uint32_t>(out.edge_face.size()));
    i = j;
  }
  return out;
}

std::vector<int> face_components(const Mesh& mesh, const MeshEdges& edges) {
  std::vector<std::uint32_t> parent(mesh.num_faces());
  std::iota(parent.begin(), parent.end(), 0u);
  auto root = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t e = 0; e < edges.size(); ++e)
    for (std::size_t k = 1; k < edges.faces_on(e); ++k) {
      auto a = root(edges.faces(e)[0]), b = root(edges.faces(e)[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<int> id(mesh.num_faces(), -1), comp(mesh.num_faces());
  int next = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    auto r = root(static_cast<std::uint32_t>(f));
    if (id[r] < 0) id[r] = next++;
    comp[f] = id[r];
  }
  return comp;
}

std::vector<bool> closed_components(const MeshEdges& edges, const std::vector<int>& component) {
  const int n = component.empty() ? 0 : *std::max_element(component.begin(), component.end()) + 1;
  std::vector<bool> closed(n, true);
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.faces_on(e) != 2) closed[component[edges.faces(e)[0]]] = false;
  return closed;
}

std::vector<std::vector<std::uint32_t>> boundary_loops(const Mesh& mesh, const MeshEdges& edges) {
  // Directed boundary edges u -> v as the one face on them runs, indexed by u.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out_edges;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::size_t n = mesh.face_size(f);
    for (std::size_t c = 0; c < n; ++c)
      if (edges.is_boundary(edges.face_edge[mesh.face_start[f] + c]))
        out_edges.push_back({mesh.face(f)[c], mesh.face(f)[(c + 1) % n]});
  }
  std::sort(out_edges.begin(), out_edges.end());
  std::vector<bool> used(out_edges.size(), false);
  auto next_from = [&](std::uint32_t u) -> std::optional<std::size_t> {
    auto it = std::lower_bound(out_edges.begin(), out_edges.end(), std::make_pair(u, std::uint32_t{0}));
    for (; it != out_edges.end() && it->first == u; ++it) {
      auto k = static_cast<std::size_t>(it - out_edges.begin());
      if (!used[k]) return k;
    }
    return std::nullopt;
  };
  std::vector<std::vector<std::uint32_t>> loops;
  for (std::size_t s = 0; s < out_edges.size(); ++s) {
    if (used[s]) continue;
    std::vector<std::uint32_t> loop;
    std::size_t k = s;
    while (true) {
      used[k] = true;
      loop.push_back(out_edges[k].first);
      if (out_edges[k].second == out_edges[s].first) break;
      auto nk = next_from(out_edges[k].second);
      if (!nk) break;  // an open chain (inconsistent orientation): kept as it is
      k = *nk;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

VertexFaces vertex_faces(const Mesh& mesh) {
  VertexFaces out;
  out.start.assign(mesh.num_vertices() + 1, 0);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) ++out.start[mesh.face(f)[c] + 1];
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) out.start[v + 1] += out.start[v];
  out.face.resize(out.start.back());
  std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) {
      const std::uint32_t v = mesh.face(f)[c];
      // Faces come in increasing order, so a face repeating v is the last one written.
      if (fill[v] > out.start[v] && out.face[fill[v] - 1] == f) continue;
      out.face[fill[v]++] = static_cast<std::uint32_t>(f);
    }
  // Compact away the slots left by faces that repeat a vertex.
  std::size_t w = 0;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    const std::size_t begin = out.start[v], end = fill[v];
    out.start[v] = static_cast<std::uint32_t>(w);
    for (std::size_t k = begin; k < end; ++k) out.face[w++] = out.face[k];
  }
  out.start[mesh.num_vertices()] = static_cast<std::uint32_t>(w);
  out.face.resize(w);
  return out;
}

Eigen::Vector3d face_area_vector(const Mesh& mesh, std::size_t f) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  const std::size_t m = mesh.face_size(f);
  for (std::size_t c = 0; c < m; ++c)
    n += mesh.vertices[mesh.face(f)[c]].cross(mesh.vertices[mesh.face(f)[(c + 1) % m]]);
  return n;
}

MeshTopology mesh_topology(const Mesh& mesh, const MeshEdges& edges) {
  MeshTopology t;
  t.vertices = mesh.num_vertices();
  t.faces = mesh.num_faces();
  t.edges = edges.size();
  const auto comp = face_components(mesh, edges);
  t.components = comp.empty() ? 0 : *std::max_element(comp.begin(), comp.end()) + 1;
  const auto loops = boundary_loops(mesh, edges);
  t.boundary_loops = static_cast<int>(loops.size());
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (!edges.is_manifold(e)) ++t.non_manifold_edges;

  // Size scale for "no area": the bounding box diagonal.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const double diag = mesh.vertices.empty() ? 0.0 : (hi - lo).norm();
  std::vector<bool> on_face(mesh.num_vertices(), false);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    std::vector<std::uint32_t> c(mesh.face(f), mesh.face(f) + mesh.face_size(f));
    for (auto v : c) on_face[v] = true;
    std::sort(c.begin(), c.end());
    const bool repeated = std::adjacent_find(c.begin(), c.end()) != c.end();
    if (repeated || face_area_vector(mesh, f).norm() <= 1e-12 * diag * diag) ++t.degenerate_faces;
  }
  t.isolated_vertices = static_cast<std::size_t>(std::count(on_face.begin(), on_face.end(), false));

  if (t.non_manifold_edges > 0) {
    t.genus = -1;
    return t;
  }
  // Per component: chi = V - E + F, b boundary loops, g = (2 - b - chi) / 2.
  std::vector<long> V(t.components, 0), E(t.components, 0), F(t.components, 0), B(t.components, 0);
  std::vector<int> vcomp(mesh.num_vertices(), -1);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    ++F[comp[f]];
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) vcomp[mesh.face(f)[c]] = comp[f];
  }
  for (int c : vcomp)
    if (c >= 0) ++V[c];
  for (std::size_t e = 0; e < edges.size(); ++e) ++E[comp[edges.faces(e)[0]]];
  for (const auto& loop : loops) ++B[vcomp[loop.front()]];
  t.genus = 0;
  for (int c = 0; c < t.components; ++c) t.genus += static_cast<int>((2 - B[c] - (V[c] - E[c] + F[c])) / 2);
  return t;
}

double mean_edge_length(const Mesh& m) {
  const MeshEdges edges = mesh_edges(m);
  double sum = 0;
  for (const auto& e : edges.edges) sum += (m.vertices[e[0]] - m.vertices[e[1]]).norm();
  return edges.size() > 0 ? sum / static_cast<double>(edges.size()) : 0;
}

}  // namespace scallop
