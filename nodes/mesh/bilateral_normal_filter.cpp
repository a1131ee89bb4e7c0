#include "nodes/mesh/bilateral_normal_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scallop {

BilateralResult bilateral_filter_normals(const Mesh& mesh, const MeshEdges& edges,
                                         const VertexFaces& around, const FaceGeometry& geometry,
                                         const BilateralOptions& o,
                                         const std::function<void(double)>& progress) {
  if (!(o.sigma_r > 0) || !std::isfinite(o.sigma_r)) throw std::invalid_argument("sigma_r must be positive");
  if (!(o.sigma_s >= 0) || !std::isfinite(o.sigma_s)) throw std::invalid_argument("sigma_s must not be negative");
  if (o.iterations < 0) throw std::invalid_argument("iterations must not be negative");
  const std::size_t F = mesh.num_faces();
  BilateralResult out;
  out.sigma_s = o.sigma_s;
  if (out.sigma_s == 0) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t e = 0; e < edges.size(); ++e)
      if (edges.faces_on(e) == 2) {
        sum += (geometry.centroid[edges.faces(e)[0]] - geometry.centroid[edges.faces(e)[1]]).norm();
        ++n;
      }
    out.sigma_s = n > 0 ? sum / n : 1.0;
    if (!(out.sigma_s > 0)) out.sigma_s = 1.0;
  }
  // N(i): the faces sharing a vertex with i, i included, each once.
  std::vector<std::uint32_t> start(F + 1, 0), ring;
  {
    std::vector<std::vector<std::uint32_t>> rings(F);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 2048), [&](const auto& r) {
      for (std::size_t f = r.begin(); f < r.end(); ++f) {
        auto& ring_f = rings[f];
        for (std::size_t c = 0; c < mesh.face_size(f); ++c) {
          const std::uint32_t v = mesh.face(f)[c];
          ring_f.insert(ring_f.end(), around.faces(v), around.faces(v) + around.count(v));
        }
        std::sort(ring_f.begin(), ring_f.end());
        ring_f.erase(std::unique(ring_f.begin(), ring_f.end()), ring_f.end());
      }
    });
    for (std::size_t f = 0; f < F; ++f) start[f + 1] = start[f] + static_cast<std::uint32_t>(rings[f].size());
    ring.resize(start[F]);
    for (std::size_t f = 0; f < F; ++f) std::copy(rings[f].begin(), rings[f].end(), ring.begin() + start[f]);
  }
  const double ks = -0.5 / (out.sigma_s * out.sigma_s), kr = -0.5 / (o.sigma_r * o.sigma_r);
  // The spatial weights times the areas do not change from one iteration to the next.
  std::vector<double> spatial(ring.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const auto& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f)
      for (std::size_t k = start[f]; k < start[f + 1]; ++k) {
        const std::uint32_t j = ring[k];
        spatial[k] = geometry.area[j] * std::exp(ks * (geometry.centroid[f] - geometry.centroid[j]).squaredNorm());
      }
  });
  std::vector<Eigen::Vector3d> n = geometry.normal, next(F);
  for (int it = 0; it < o.iterations; ++it) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, F, 4096), [&](const auto& r) {
      for (std::size_t f = r.begin(); f < r.end(); ++f) {
        if (n[f].squaredNorm() == 0) {
          next[f] = n[f];
          continue;
        }
        Eigen::Vector3d s = Eigen::Vector3d::Zero();
        for (std::size_t k = start[f]; k < start[f + 1]; ++k) {
          const Eigen::Vector3d& nj = n[ring[k]];
          s += spatial[k] * std::exp(kr * (n[f] - nj).squaredNorm()) * nj;
        }
        const double len = s.norm();
        next[f] = len > 0 ? Eigen::Vector3d(s / len) : n[f];
      }
    });
    n.swap(next);
    out.iterations = it + 1;
    if (progress) progress(static_cast<double>(it + 1) / o.iterations);
  }
  out.normals = std::move(n);
  return out;
}

}  // namespace scallop
