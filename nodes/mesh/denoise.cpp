#include "nodes/mesh/denoise.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/vertex_update.h"

namespace scallop {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Refuses what the filters cannot take, with the reason and what to do.
void check_input(const Mesh& mesh, const MeshEdges& edges) {
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh is empty (no faces)");
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    if (!mesh.vertices[v].allFinite())
      throw std::invalid_argument("vertex " + std::to_string(v) + " has a non-finite coordinate");
  std::size_t other = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    if (mesh.face_size(f) != 3) ++other;
  if (other > 0)
    throw std::invalid_argument(std::to_string(other) + " of " + std::to_string(mesh.num_faces()) +
                                " faces are not triangles: triangulate the mesh first");
  std::size_t non_manifold = 0;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (!edges.is_manifold(e)) ++non_manifold;
  if (non_manifold > 0)
    throw std::invalid_argument(std::to_string(non_manifold) + (non_manifold == 1 ? " edge has" : " edges have") +
                                " 3 or more faces: run mesh.repair first");
}

}  // namespace

MeshDenoiseResult denoise_mesh(const Mesh& mesh, const MeshDenoiseOptions& o,
                               const std::function<void(double)>& progress) {
  if (o.vertex_iterations < 0) throw std::invalid_argument("vertex_iterations must not be negative");
  for (auto v : mesh.face_vertices)
    if (v >= mesh.num_vertices()) throw std::invalid_argument("a face indexes past the vertices");
  const auto t0 = std::chrono::steady_clock::now();
  const MeshEdges edges = mesh_edges(mesh);
  check_input(mesh, edges);
  const FaceGeometry before = face_geometry(mesh);
  const VertexFaces around = vertex_faces(mesh);
  // Progress: the filter to 0.8, the vertex update to 1.
  const double split = o.vertex_iterations > 0 ? 0.8 : 1.0;
  auto filter_progress = [&](double f) {
    if (progress) progress(split * f);
  };
  MeshDenoiseResult out;
  std::vector<Eigen::Vector3d> normals;
  if (o.method == MeshDenoiseMethod::Tgv) {
    TgvResult r = tgv_filter_normals(mesh, edges, before, o.tgv, filter_progress);
    normals = std::move(r.normals);
    out.iterations = r.iterations;
    out.last_turn_mean_deg = r.last_turn_mean_deg;
    out.last_turn_max_deg = r.last_turn_max_deg;
    out.cg_steps = r.cg_steps;
  } else {
    BilateralResult r = bilateral_filter_normals(mesh, edges, around, before, o.bilateral, filter_progress);
    normals = std::move(r.normals);
    out.iterations = r.iterations;
  }
  out.filter_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> x = update_vertices(mesh, around, normals, o.vertex_iterations, [&](double f) {
    if (progress) progress(split + (1 - split) * f);
  });
  out.vertex_seconds = seconds_since(t1);

  // What changed.
  const FaceGeometry after = face_geometry(mesh, x);
  double area = 0, turned = 0;
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const double a = angle_deg(before.normal[f], after.normal[f]);
    turned += before.area[f] * a;
    area += before.area[f];
    out.normal_change_max_deg = std::max(out.normal_change_max_deg, a);
  }
  out.normal_change_mean_deg = area > 0 ? turned / area : 0;
  std::size_t moved = 0;
  double sum = 0;
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    if (around.count(v) > 0) {
      const double d = (x[v] - mesh.vertices[v]).norm();
      sum += d;
      out.move_max = std::max(out.move_max, d);
      ++moved;
    }
  out.move_mean = moved > 0 ? sum / moved : 0;

  out.mesh = mesh;
  out.mesh.vertices = std::move(x);
  if (mesh.has_normals()) {
    // Area-weighted vertex normals of the moved mesh.
    auto& n = out.mesh.normals;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.num_vertices(), 4096), [&](const auto& r) {
      for (std::size_t v = r.begin(); v < r.end(); ++v) {
        Eigen::Vector3d s = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < around.count(v); ++k) {
          const auto f = around.faces(v)[k];
          s += after.area[f] * after.normal[f];
        }
        if (s.norm() > 0) n[v] = s.normalized();
      }
    });
  }
  return out;
}

}  // namespace scallop
