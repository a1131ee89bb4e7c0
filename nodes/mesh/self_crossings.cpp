#include "nodes/mesh/self_crossings.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <deque>

#include "nodes/mesh/mesh_distance.h"

namespace scallop {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;
using Face = Surface::Face_index;

// Whether the point just off triangle f's centre along its normal lies inside the mesh (by the
// rays' parity): the face faces inward.
bool faces_inward(const Surface& s, const MeshDistance& rays, Face f) {
  const auto h = s.halfedge(f);
  const Kernel::Point_3 &a = s.point(s.source(h)), &b = s.point(s.target(h)), &c = s.point(s.target(s.next(h)));
  const Kernel::Vector_3 n = CGAL::cross_product(b - a, c - a);
  const double length = std::sqrt(n.squared_length());
  if (!(length > 0)) return false;
  const double shortest = std::sqrt(std::min({(b - a).squared_length(), (c - b).squared_length(), (a - c).squared_length()}));
  const Kernel::Point_3 q = CGAL::centroid(a, b, c) + n * (1e-3 * shortest / length);
  return rays.inside_by_rays(Eigen::Vector3d(q.x(), q.y(), q.z()));
}

}  // namespace

SelfCrossings self_crossings(const Mesh& mesh) {
  SelfCrossings out;
  Surface s;
  for (const Eigen::Vector3d& v : mesh.vertices) s.add_vertex(Kernel::Point_3(v.x(), v.y(), v.z()));
  std::vector<std::size_t> polygon_of;  // the triangle's polygon
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::uint32_t* c = mesh.face(f);
    bool fits = true;
    for (std::size_t i = 1; i + 1 < mesh.face_size(f); ++i) {
      const Face t = s.add_face(Surface::Vertex_index(c[0]), Surface::Vertex_index(c[i]), Surface::Vertex_index(c[i + 1]));
      if (t == Surface::null_face()) {
        fits = false;
        continue;
      }
      polygon_of.push_back(f);
    }
    out.faces_left_out += !fits;
  }
  if (s.number_of_faces() == 0) return out;

  std::vector<std::pair<Face, Face>> crossing;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_if_available_tag>(s, std::back_inserter(crossing));
  std::vector<char> tangled(s.number_of_faces(), 0);
  std::deque<Face> grow;
  for (const auto& [f, g] : crossing) {
    if (f == g) continue;  // a face without area
    const std::size_t a = polygon_of[f], b = polygon_of[g];
    if (a == b) continue;  // a polygon's own fan folded over itself
    out.pairs.push_back({std::min(a, b), std::max(a, b)});
    for (Face t : {f, g})
      if (!tangled[t]) tangled[t] = 1, grow.push_back(t);
  }
  if (out.pairs.empty()) return out;
  std::sort(out.pairs.begin(), out.pairs.end());
  out.pairs.erase(std::unique(out.pairs.begin(), out.pairs.end()), out.pairs.end());

  // Grown across edges while the faces reached face inward.
  const MeshDistance rays(mesh);
  std::vector<char> tested(s.number_of_faces(), 0);
  while (!grow.empty()) {
    const Face f = grow.front();
    grow.pop_front();
    for (const auto h : CGAL::halfedges_around_face(s.halfedge(f), s)) {
      const Face g = s.face(s.opposite(h));
      if (g == Surface::null_face() || tangled[g] || tested[g]) continue;
      tested[g] = 1;
      if (faces_inward(s, rays, g)) tangled[g] = 2, grow.push_back(g);
    }
  }
  std::vector<char> polygon(mesh.num_faces(), 0);
  for (Face t : s.faces())
    if (tangled[t]) polygon[polygon_of[t]] = std::max(polygon[polygon_of[t]], tangled[t]);
  for (std::size_t f = 0; f < polygon.size(); ++f) {
    if (!polygon[f]) continue;
    out.tangled.push_back(f);
    out.inward += polygon[f] == 2;
  }
  return out;
}

TangleKeepOut tangle_keep_out(const Mesh& mesh, const SelfCrossings& crossings, double margin) {
  TangleKeepOut out;
  if (margin == 0 || crossings.tangled.empty()) return out;
  double length = 0;
  std::size_t edges = 0;
  for (std::size_t f : crossings.tangled)
    for (std::size_t k = 0; k < mesh.face_size(f); ++k, ++edges)
      length += (mesh.vertices[mesh.face(f)[(k + 1) % mesh.face_size(f)]] - mesh.vertices[mesh.face(f)[k]]).norm();
  if (edges == 0 || !(length > 0)) return out;
  out.margin = margin > 0 ? margin : 2 * length / double(edges);
  const double step = out.margin / 4;
  for (std::size_t f : crossings.tangled) {
    const std::uint32_t* c = mesh.face(f);
    for (std::size_t i = 1; i + 1 < mesh.face_size(f); ++i) {
      const Eigen::Vector3d &a = mesh.vertices[c[0]], &b = mesh.vertices[c[i]], &d = mesh.vertices[c[i + 1]];
      const double longest = std::max({(b - a).norm(), (d - b).norm(), (a - d).norm()});
      const int n = std::max(1, int(std::ceil(longest / step)));
      for (int u = 0; u <= n; ++u)
        for (int v = 0; u + v <= n; ++v) out.samples.push_back(a + (b - a) * (double(u) / n) + (d - a) * (double(v) / n));
    }
  }
  return out;
}

}  // namespace scallop
