#include "nodes/mesh/face_geometry.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scallop {

FaceGeometry face_geometry(const Mesh& mesh) { return face_geometry(mesh, mesh.vertices); }

FaceGeometry face_geometry(const Mesh& mesh, const std::vector<Eigen::Vector3d>& V) {
  const std::size_t F = mesh.num_faces();
  FaceGeometry g;
  g.normal.resize(F);
  g.area.resize(F);
  g.centroid.resize(F);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const auto& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      const std::uint32_t* c = mesh.face(f);
      const std::size_t m = mesh.face_size(f);
      // Newell's vector about the first corner (no cancellation far from the origin).
      const Eigen::Vector3d& o = V[c[0]];
      Eigen::Vector3d n = Eigen::Vector3d::Zero(), s = Eigen::Vector3d::Zero();
      for (std::size_t k = 0; k < m; ++k) {
        n += (V[c[k]] - o).cross(V[c[(k + 1) % m]] - o);
        s += V[c[k]];
      }
      const double len = n.norm();
      g.area[f] = 0.5 * len;
      g.normal[f] = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
      g.centroid[f] = s / static_cast<double>(m);
    }
  });
  return g;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
}

std::vector<Eigen::Vector3d> vertex_normals(const Mesh& mesh) {
  const FaceGeometry g = face_geometry(mesh);
  std::vector<Eigen::Vector3d> n(mesh.num_vertices(), Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const std::size_t m = mesh.face_size(f);
    const std::uint32_t* c = mesh.face(f);
    for (std::size_t i = 0; i < m; ++i) {
      const Eigen::Vector3d& p = mesh.vertices[c[i]];
      const double angle = angle_deg(mesh.vertices[c[(i + m - 1) % m]] - p, mesh.vertices[c[(i + 1) % m]] - p);
      n[c[i]] += angle * g.normal[f];
    }
  }
  for (auto& v : n)
    if (v.norm() > 0) v.normalize();
  return n;
}

FannedTriangles fan_triangles(const Mesh& mesh, const std::vector<std::size_t>& faces) {
  FannedTriangles out;
  std::vector<std::size_t> local(mesh.num_vertices(), SIZE_MAX);
  auto vertex = [&](std::uint32_t v) {
    if (local[v] == SIZE_MAX) local[v] = out.points.size(), out.points.push_back(mesh.vertices[v]);
    return local[v];
  };
  for (std::size_t f : faces) {
    out.first_triangle.push_back(out.triangles.size());
    const std::uint32_t* c = mesh.face(f);
    for (std::size_t k = 1; k + 1 < mesh.face_size(f); ++k) out.triangles.push_back({vertex(c[0]), vertex(c[k]), vertex(c[k + 1])});
  }
  return out;
}

}  // namespace scallop
