#include "nodes/mesh/merge_solids.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "nodes/geom/union_find.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

// The faces `faces` of `mesh` as a triangle mesh (each polygon fanned from its first corner).
SurfaceMesh triangle_mesh(const Mesh& mesh, const std::vector<std::size_t>& faces) {
  const FannedTriangles fan = fan_triangles(mesh, faces);
  std::vector<Point> points;
  for (const auto& p : fan.points) points.emplace_back(p.x(), p.y(), p.z());
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(points, fan.triangles, tm);
  return tm;
}

}  // namespace

MergeSolidsReport merge_overlapping_solids(Mesh& mesh) {
  MergeSolidsReport report;
  const MeshEdges edges = mesh_edges(mesh);
  const std::vector<int> comp = face_components(mesh, edges);
  const std::vector<bool> closed = closed_components(edges, comp);
  const int n_comp = static_cast<int>(closed.size());
  if (n_comp < 2) return report;
  std::vector<std::vector<std::size_t>> faces_of(n_comp);
  std::vector<Eigen::AlignedBox3d> box(n_comp);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    faces_of[comp[f]].push_back(f);
    for (std::size_t k = 0; k < mesh.face_size(f); ++k) box[comp[f]].extend(mesh.vertices[mesh.face(f)[k]]);
  }

  // Closed components whose surfaces cross, grouped.
  std::vector<SurfaceMesh> solid(n_comp);
  for (int c = 0; c < n_comp; ++c)
    if (closed[c]) solid[c] = triangle_mesh(mesh, faces_of[c]);
  UnionFind groups(n_comp);
  bool any = false;
  for (int a = 0; a < n_comp; ++a)
    for (int b = a + 1; b < n_comp; ++b)
      if (closed[a] && closed[b] && box[a].intersects(box[b]) && PMP::do_intersect(solid[a], solid[b]))
        groups.join(std::uint32_t(a), std::uint32_t(b)), any = true;
  if (!any) return report;

  std::vector<std::vector<int>> members(n_comp);
  for (int c = 0; c < n_comp; ++c) members[groups.root(std::uint32_t(c))].push_back(c);
  std::vector<bool> merged(n_comp, false);
  std::vector<SurfaceMesh> unions;
  for (const auto& group : members) {
    if (group.size() < 2) continue;
    // Corefinement wants solids that do not intersect themselves; a group with one is left apart.
    bool ok = std::none_of(group.begin(), group.end(), [&](int c) { return PMP::does_self_intersect(solid[c]); });
    // Each outward on its own: solids whose surfaces cross are no cavity of each other, though
    // orient_to_bound_a_volume, seeing one partly inside the other, may have turned it inward.
    for (int c : group)
      if (ok && PMP::volume(solid[c]) < 0) PMP::reverse_face_orientations(solid[c]);
    SurfaceMesh result = solid[group[0]];
    for (std::size_t k = 1; ok && k < group.size(); ++k) {
      SurfaceMesh other = solid[group[k]], united;
      ok = PMP::corefine_and_compute_union(result, other, united);
      result = std::move(united);
    }
    if (!ok) {
      report.solids_not_merged += group.size();
      continue;
    }
    for (int c : group) merged[c] = true;
    report.solids_merged += group.size() - 1;
    // The cut leaves slivers of (nearly) no area where the solids' faces met nearly along a line
    // (16 on the ABC plate), which QuadriFlow refuses: degenerate ones removed, then edges shorter
    // than 1e-7 of the diagonal collapsed and triangles with an angle over 179.7 degrees flipped
    // away (needles longer than that are the CAD's own and stay); a vertex where two sheets touch
    // is split in two.
    PMP::remove_degenerate_faces(result);
    {
      Eigen::AlignedBox3d all;
      for (auto v : result.vertices()) all.extend(Eigen::Vector3d(result.point(v).x(), result.point(v).y(), result.point(v).z()));
      PMP::experimental::remove_almost_degenerate_faces(result, -0.99999, 1e9, 1e-7 * all.diagonal().norm());
    }
    PMP::duplicate_non_manifold_vertices(result);
    result.collect_garbage();
    unions.push_back(std::move(result));
  }
  if (report.solids_merged == 0) return report;

  // The faces kept, in their order, then the unions' triangles; vertices renumbered in order of
  // first use (the merged solids' own are gone).
  Mesh out;
  std::vector<std::uint32_t> index(mesh.num_vertices(), UINT32_MAX);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    if (merged[comp[f]]) continue;
    std::vector<std::uint32_t> corners;
    for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
      std::uint32_t& v = index[mesh.face(f)[k]];
      if (v == UINT32_MAX) v = static_cast<std::uint32_t>(out.vertices.size()), out.vertices.push_back(mesh.vertices[mesh.face(f)[k]]);
      corners.push_back(v);
    }
    out.add_face_range(corners);
  }
  for (const SurfaceMesh& u : unions) {
    const auto first = static_cast<std::uint32_t>(out.vertices.size());
    for (auto v : u.vertices()) out.vertices.emplace_back(u.point(v).x(), u.point(v).y(), u.point(v).z());
    for (auto f : u.faces()) {
      std::vector<std::uint32_t> corners;
      for (auto v : CGAL::vertices_around_face(u.halfedge(f), u)) corners.push_back(first + std::uint32_t(v));
      out.add_face_range(corners);
    }
  }
  mesh = std::move(out);
  return report;
}

}  // namespace scallop
