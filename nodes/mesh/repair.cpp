#include "nodes/mesh/repair.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/merge_solids.h"
#include "nodes/mesh/mesh_topology.h"

namespace scallop {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Polygons = std::vector<std::vector<std::size_t>>;

// Counts what orient_polygon_soup does (it takes its visitor by value: the counts live outside).
struct OrientCounter : PMP::Default_orientation_visitor {
  RepairReport* report;
  std::set<std::pair<std::size_t, std::size_t>>* cut_edges;  // called once per face on such an edge
  void non_manifold_edge(std::size_t a, std::size_t b, std::size_t) {
    if (cut_edges->insert({std::min(a, b), std::max(a, b)}).second) ++report->non_manifold_edges_cut;
  }
  void duplicated_vertex(std::size_t, std::size_t) { ++report->non_manifold_vertices_split; }
  void polygon_orientation_reversed(std::size_t) { ++report->faces_reversed; }
};

void to_soup(const Mesh& mesh, std::vector<Point>& points, Polygons& polygons) {
  points.clear();
  polygons.clear();
  points.reserve(mesh.num_vertices());
  for (const auto& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  polygons.reserve(mesh.num_faces());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) polygons.emplace_back(mesh.face(f), mesh.face(f) + mesh.face_size(f));
}

Mesh from_soup(const std::vector<Point>& points, const Polygons& polygons) {
  Mesh mesh;
  mesh.vertices.reserve(points.size());
  for (const Point& p : points) mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  for (const auto& polygon : polygons) mesh.add_face_range(polygon);
  return mesh;
}

// The cleaning of CGAL's repair_polygon_soup, its six steps called one by one in its order (as
// CGAL 5.5's internal::Polygon_soup_fixer does) so that each one's count can be reported.
void clean_soup(std::vector<Point>& points, Polygons& polygons, RepairReport& r) {
  const Kernel traits;
  r.points_merged = PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
  r.faces_simplified = PMP::internal::simplify_polygons_in_polygon_soup(points, polygons, traits);
  r.pinched_faces_split = PMP::internal::split_pinched_polygons_in_polygon_soup(points, polygons, traits);
  r.degenerate_faces_removed = PMP::internal::remove_invalid_polygons_in_polygon_soup(points, polygons);
  r.duplicate_faces_removed = PMP::merge_duplicate_polygons_in_polygon_soup(points, polygons);
  r.isolated_vertices_removed = PMP::remove_isolated_points_in_polygon_soup(points, polygons);
}

// Whether the triangle (a, b, c) runs round the other way in face t of `tm`.
bool reversed_in(const SurfaceMesh& tm, SurfaceMesh::Face_index t, const std::array<std::size_t, 3>& abc) {
  std::array<std::size_t, 3> now{};
  int k = 0;
  for (auto v : CGAL::vertices_around_face(tm.halfedge(t), tm)) now[k++] = v;
  const auto at = std::find(now.begin(), now.end(), abc[0]) - now.begin();
  return now[(at + 1) % 3] != abc[1];
}

// Turns the closed components of `mesh` (every edge on exactly two faces) so that they bound a
// volume, by CGAL's orient_to_bound_a_volume on a fan triangulation of them (it wants
// triangles); a face is reversed when its first triangle was. Returns the faces reversed.
std::size_t orient_closed_components(Mesh& mesh) {
  const MeshEdges edges = mesh_edges(mesh);
  const std::vector<int> comp = face_components(mesh, edges);
  const std::vector<bool> closed = closed_components(edges, comp);

  // Only the closed components' vertices: CGAL's volume_connected_components crashes on an
  // isolated vertex (CGAL 5.5.1).
  std::vector<std::size_t> closed_faces;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    if (closed[comp[f]]) closed_faces.push_back(f);
  const FannedTriangles fan = fan_triangles(mesh, closed_faces);
  std::vector<Point> points;
  for (const auto& p : fan.points) points.emplace_back(p.x(), p.y(), p.z());
  const auto& triangles = fan.triangles;
  if (triangles.empty() || !PMP::is_polygon_soup_a_polygon_mesh(triangles)) return 0;
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(points, triangles, tm);
  if (!CGAL::is_closed(tm)) return 0;
  PMP::orient_to_bound_a_volume(tm);
  // polygon_soup_to_polygon_mesh adds every point and then every triangle, in order: vertex i of
  // tm is point i, face i is triangle i.
  std::size_t turned = 0;
  for (std::size_t k = 0; k < closed_faces.size(); ++k) {
    const std::size_t f = closed_faces[k], first = fan.first_triangle[k];
    const auto t = SurfaceMesh::Face_index(static_cast<SurfaceMesh::size_type>(first));
    if (!reversed_in(tm, t, triangles[first])) continue;
    std::reverse(mesh.face_vertices.begin() + mesh.face_start[f] + 1, mesh.face_vertices.begin() + mesh.face_start[f + 1]);
    ++turned;
  }
  return turned;
}

}  // namespace

Mesh repair_mesh(const Mesh& soup, const RepairOptions& options, RepairReport& report) {
  report = RepairReport{};
  if (soup.num_faces() == 0) throw std::invalid_argument("the mesh has no faces");
  for (auto v : soup.face_vertices)
    if (v >= soup.num_vertices())
      throw std::invalid_argument("a face has corner " + std::to_string(v) + " but there are " +
                                  std::to_string(soup.num_vertices()) + " vertices");
  std::vector<Point> points;
  Polygons polygons;
  to_soup(soup, points, polygons);
  clean_soup(points, polygons, report);
  if (polygons.empty()) throw std::invalid_argument("no face is left: every one was degenerate");

  std::set<std::pair<std::size_t, std::size_t>> cut_edges;
  OrientCounter counter;
  counter.report = &report;
  counter.cut_edges = &cut_edges;
  PMP::orient_polygon_soup(points, polygons, CGAL::parameters::visitor(counter));
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    throw std::runtime_error("CGAL could not make a polygon mesh of the faces even after orienting them");

  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  report.borders_stitched = PMP::stitch_borders(sm);
  report.non_manifold_vertices_split += PMP::duplicate_non_manifold_vertices(sm);
  if (options.fill_holes > 0) {
    std::vector<SurfaceMesh::Halfedge_index> cycles;
    PMP::extract_boundary_cycles(sm, std::back_inserter(cycles));
    for (auto h : cycles) {
      std::size_t length = 0;
      for (auto g : CGAL::halfedges_around_face(h, sm)) (void)g, ++length;
      if (length > std::size_t(options.fill_holes)) {
        ++report.holes_left;
        continue;
      }
      std::vector<SurfaceMesh::Face_index> faces;
      std::vector<SurfaceMesh::Vertex_index> vertices;
      PMP::triangulate_and_refine_hole(sm, h, std::back_inserter(faces), std::back_inserter(vertices));
      ++(faces.empty() ? report.holes_left : report.holes_filled);
    }
  }
  if (options.slivers > 0 && CGAL::is_triangle_mesh(sm) && sm.number_of_edges() > 0) {
    double mean = 0;
    for (auto e : sm.edges()) mean += PMP::edge_length(e, sm);
    const double size = options.slivers * mean / double(sm.number_of_edges());
    const double cap = std::cos(160 * std::numbers::pi / 180), needle = 4;
    const auto slivers = [&] {
      std::size_t n = 0;
      for (auto f : sm.faces()) {
        const auto h = PMP::is_needle_triangle_face(f, sm, needle);
        const auto c = PMP::is_cap_triangle_face(f, sm, cap);
        n += (h != SurfaceMesh::null_halfedge() && PMP::edge_length(h, sm) <= size) ||
             (c != SurfaceMesh::null_halfedge() &&
              CGAL::squared_distance(sm.point(sm.target(sm.next(c))), Kernel::Line_3(sm.point(sm.source(c)), sm.point(sm.target(c)))) <= size * size);
      }
      return n;
    };
    report.slivers_found = slivers();
    PMP::experimental::remove_almost_degenerate_faces(sm.faces(), sm, cap, needle, size,
                                                      CGAL::parameters::flip_triangle_height_threshold(size));
    report.slivers_left = slivers();
  }
  sm.collect_garbage();
  points.clear();
  polygons.clear();
  PMP::polygon_mesh_to_polygon_soup(sm, points, polygons);
  Mesh mesh = from_soup(points, polygons);
  if (options.orient_outward) report.faces_turned_outward = orient_closed_components(mesh);
  if (options.orient_outward && options.merge_overlapping) {
    const MergeSolidsReport merged = merge_overlapping_solids(mesh);
    report.solids_merged = merged.solids_merged, report.solids_not_merged = merged.solids_not_merged;
  }
  return mesh;
}

}  // namespace scallop
