#include "nodes/mesh/vertex_update.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scallop {

std::vector<Eigen::Vector3d> update_vertices(const Mesh& mesh, const VertexFaces& around,
                                             const std::vector<Eigen::Vector3d>& normals,
                                             int iterations,
                                             const std::function<void(double)>& progress) {
  const std::size_t F = mesh.num_faces(), V = mesh.num_vertices();
  std::vector<Eigen::Vector3d> x = mesh.vertices, next(V), centroid(F);
  for (int it = 0; it < iterations; ++it) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const auto& r) {
      for (std::size_t f = r.begin(); f < r.end(); ++f) {
        Eigen::Vector3d s = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < mesh.face_size(f); ++c) s += x[mesh.face(f)[c]];
        centroid[f] = s / static_cast<double>(mesh.face_size(f));
      }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, 4096), [&](const auto& r) {
      for (std::size_t v = r.begin(); v < r.end(); ++v) {
        Eigen::Vector3d move = Eigen::Vector3d::Zero();
        int used = 0;
        for (std::size_t k = 0; k < around.count(v); ++k) {
          const std::uint32_t f = around.faces(v)[k];
          const Eigen::Vector3d& n = normals[f];
          if (n.squaredNorm() == 0) continue;
          move += n * n.dot(centroid[f] - x[v]);
          ++used;
        }
        next[v] = used > 0 ? Eigen::Vector3d(x[v] + move / used) : x[v];
      }
    });
    x.swap(next);
    if (progress) progress(static_cast<double>(it + 1) / iterations);
  }
  return x;
}

}  // namespace scallop
