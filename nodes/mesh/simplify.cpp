#include "nodes/mesh/simplify.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Constrained_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "nodes/mesh/mesh_distance.h"

namespace scallop {
namespace {

namespace SMS = CGAL::Surface_mesh_simplification;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using EdgeFlags = SurfaceMesh::Property_map<SurfaceMesh::Edge_index, bool>;

// Vertex i of `mesh` becomes vertex i of the result; refuses what Surface_mesh cannot hold.
SurfaceMesh to_surface_mesh(const Mesh& mesh) {
  SurfaceMesh sm;
  for (const auto& p : mesh.vertices) sm.add_vertex(Point(p.x(), p.y(), p.z()));
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    if (mesh.face_size(f) != 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(mesh.face_size(f)) +
                                  " corners: only triangle meshes are simplified");
    const auto* c = mesh.face(f);
    if (sm.add_face(SurfaceMesh::Vertex_index(c[0]), SurfaceMesh::Vertex_index(c[1]),
                    SurfaceMesh::Vertex_index(c[2])) == SurfaceMesh::null_face())
      throw std::invalid_argument("face " + std::to_string(f) +
                                  " makes the mesh non-manifold or inconsistently oriented: run mesh.repair first");
  }
  return sm;
}

// Refuses a collapse that would leave a vertex with more than `max_valence` edges. A vertex on a
// feature edge never moves, so without a cap its neighbours keep collapsing into it: fans of
// slivers along every feature curve, which QuadriFlow gets as input, and CGAL's cost per collapse
// grows with the square of their valence (on the ABC plate's 200 000-point cloud, 18 642 feature
// edges, the collapse took 36 s).
struct ValenceCap {
  const SurfaceMesh* mesh;
  std::size_t max_valence;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile,
                                                      boost::optional<typename Profile::Point> placement) const {
    if (!placement) return placement;
    // The merged vertex keeps both ends' edges but the collapsed one, and one of each pair that
    // meets at a face's third corner.
    const std::size_t merged_away = 2 + (profile.left_face_exists() ? 1 : 0) + (profile.right_face_exists() ? 1 : 0);
    if (mesh->degree(profile.v0()) + mesh->degree(profile.v1()) > max_valence + merged_away) return boost::none;
    return placement;
  }
};

}  // namespace

Mesh simplify_mesh(const Mesh& mesh, const SimplifyOptions& options, SimplifyReport& report) {
  report = SimplifyReport{};
  report.faces_before = mesh.num_faces();
  report.vertices_before = mesh.num_vertices();
  SurfaceMesh sm = to_surface_mesh(mesh);

  EdgeFlags constrained = sm.add_property_map<SurfaceMesh::Edge_index, bool>("e:constrained", false).first;
  for (const auto& e : mesh.feature_edges) {
    const auto h = sm.halfedge(SurfaceMesh::Vertex_index(e[0]), SurfaceMesh::Vertex_index(e[1]));
    if (h == SurfaceMesh::null_halfedge())
      throw std::invalid_argument("feature edge " + std::to_string(e[0]) + "-" + std::to_string(e[1]) +
                                  " is not an edge of the mesh");
    constrained[sm.edge(h)] = true;
  }
  for (auto e : sm.edges()) {
    if (sm.is_border(e)) {
      constrained[e] = true;
      ++report.border_edges;
    } else if (constrained[e]) {
      ++report.feature_edges;
    }
  }

  if (mesh.num_faces() > static_cast<std::size_t>(options.target_faces)) {
    using Policies = SMS::GarlandHeckbert_plane_policies<SurfaceMesh, Kernel>;
    using Placement = SMS::Bounded_normal_change_placement<SMS::Constrained_placement<Policies, EdgeFlags>>;
    Policies policies(sm);
    const Placement placement(SMS::Constrained_placement<Policies, EdgeFlags>(constrained, policies));
    // A closed triangle mesh has 3/2 as many edges as faces.
    SMS::Count_stop_predicate<SurfaceMesh> stop(static_cast<std::size_t>(options.target_faces) * 3 / 2);
    SMS::edge_collapse(sm, stop,
                       CGAL::parameters::edge_is_constrained_map(constrained)
                           .get_cost(policies)
                           .get_placement(placement)
                           .filter(ValenceCap{&sm, static_cast<std::size_t>(options.max_valence)}));
  }

  // Back to a Mesh, renumbered densely (edge_collapse leaves removed elements as garbage).
  Mesh out;
  std::vector<std::uint32_t> index(sm.num_vertices(), 0);  // num_vertices counts the removed too
  for (auto v : sm.vertices()) {
    index[v.idx()] = static_cast<std::uint32_t>(out.vertices.size());
    const Point& p = sm.point(v);
    out.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  for (auto f : sm.faces()) {
    std::vector<std::uint32_t> corners;
    for (auto v : sm.vertices_around_face(sm.halfedge(f))) corners.push_back(index[v.idx()]);
    out.add_face_range(corners);
  }
  for (auto e : sm.edges()) {
    if (!constrained[e] || sm.is_border(e)) continue;
    std::uint32_t a = index[sm.vertex(e, 0).idx()], b = index[sm.vertex(e, 1).idx()];
    out.feature_edges.push_back({std::min(a, b), std::max(a, b)});
  }
  std::sort(out.feature_edges.begin(), out.feature_edges.end());

  for (auto v : sm.vertices()) report.max_valence = std::max<std::size_t>(report.max_valence, sm.degree(v));
  report.faces_after = out.num_faces();
  report.vertices_after = out.num_vertices();
  const auto d = distances_to_mesh(mesh.vertices, out);
  for (double x : d) report.max_distance = std::max(report.max_distance, x);
  return out;
}

}  // namespace scallop
