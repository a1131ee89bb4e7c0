#include "nodes/mesh/sharp_edges.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nodes/mesh/face_geometry.h"

namespace scallop {

SharpEdges sharp_edges(const Mesh& mesh, const MeshEdges& edges, double theta, double fold) {
  if (!(theta >= 0 && theta < 180)) throw std::invalid_argument("the angle must lie in [0, 180) degrees");
  if (!(fold > theta && fold <= 180))
    throw std::invalid_argument("the fold angle must lie above the angle and at most 180 degrees");
  const FaceGeometry g = face_geometry(mesh);
  SharpEdges out;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges.faces_on(e) == 1) {
      ++out.boundary_edges;
      continue;
    }
    if (edges.faces_on(e) > 2) {
      ++out.non_manifold_edges;
      continue;
    }
    const Eigen::Vector3d& a = g.normal[edges.faces(e)[0]];
    const Eigen::Vector3d& b = g.normal[edges.faces(e)[1]];
    if (a.squaredNorm() == 0 || b.squaredNorm() == 0) continue;
    const double turn = angle_deg(a, b);
    if (turn > fold) {
      ++out.folds;
    } else if (turn > theta) {
      out.edges.push_back(edges.edges[e]);
      out.length += (mesh.vertices[edges.edges[e][0]] - mesh.vertices[edges.edges[e][1]]).norm();
    }
  }
  // The sharp edges at each vertex (CSR).
  const std::size_t V = mesh.num_vertices(), S = out.edges.size();
  std::vector<std::uint32_t> start(V + 1, 0), at(2 * S);
  for (const auto& e : out.edges) ++start[e[0] + 1], ++start[e[1] + 1];
  for (std::size_t v = 0; v < V; ++v) start[v + 1] += start[v];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < S; ++k)
      for (auto v : out.edges[k]) at[fill[v]++] = static_cast<std::uint32_t>(k);
  }
  auto degree = [&](std::uint32_t v) { return start[v + 1] - start[v]; };
  for (std::uint32_t v = 0; v < V; ++v)
    if (degree(v) >= 3) out.corners.push_back(v);

  std::vector<bool> used(S, false);
  auto edge_length = [&](std::size_t k) {
    return (mesh.vertices[out.edges[k][0]] - mesh.vertices[out.edges[k][1]]).norm();
  };
  // Walks from v along sharp edge k until a vertex whose degree is not 2 (or back at the start).
  auto walk = [&](std::uint32_t v, std::size_t k) {
    FeatureCurve c;
    c.vertices.push_back(v);
    const std::uint32_t first = v;
    while (true) {
      used[k] = true;
      c.length += edge_length(k);
      v = out.edges[k][0] == v ? out.edges[k][1] : out.edges[k][0];
      if (v == first) {
        c.closed = true;
        break;
      }
      c.vertices.push_back(v);
      if (degree(v) != 2) break;
      const std::uint32_t* e = at.data() + start[v];
      k = e[0] == k ? e[1] : e[0];
      if (used[k]) break;
    }
    return c;
  };
  for (std::uint32_t v = 0; v < V; ++v)
    if (degree(v) != 2)
      for (std::size_t i = start[v]; i < start[v + 1]; ++i)
        if (!used[at[i]]) out.curves.push_back(walk(v, at[i]));
  for (std::uint32_t v = 0; v < V; ++v)
    for (std::size_t i = start[v]; i < start[v + 1]; ++i)
      if (!used[at[i]]) out.curves.push_back(walk(v, at[i]));
  return out;
}

}  // namespace scallop
