#include "nodes/mesh/cloud_envelope.h"

#include "nodes/mesh/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nodes/geom/kd_tree.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_distance.h"

namespace scallop {

CloudEnvelope cloud_envelope(const Mesh& mesh, const std::vector<Eigen::Vector3d>& points, int k, double max_gap,
                             double bend_spacings, bool exact_feature_edges) {
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh has no face");
  if (k < 1) throw std::invalid_argument("k must be >= 1");
  if (points.size() < std::size_t(k) || points.size() < 2)
    throw std::invalid_argument("the cloud has " + std::to_string(points.size()) + " points, fewer than k = " +
                                std::to_string(k) + " (and 2)");
  for (const auto& p : points)
    if (!p.allFinite()) throw std::invalid_argument("the cloud has a point that is not finite");
  if (!(max_gap >= 0)) throw std::invalid_argument("max_gap must be >= 0");
  if (!(bend_spacings >= 0)) throw std::invalid_argument("bend must be >= 0");

  CloudEnvelope e;
  const MeshDistance distance(mesh);
  e.residual.resize(points.size());
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) { e.residual[i] = distance.signed_distance(points[i]); });

  PointsAdaptor<Eigen::Vector3d> adaptor{points};
  KdTree<Eigen::Vector3d, 3> tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();

  // The median spacing of the cloud: from every 16th point to its nearest other point.
  std::vector<double> nearest;
  for (std::size_t i = 0; i < points.size(); i += 16) {
    std::uint32_t idx[2];
    double d2[2];
    tree.knnSearch(points[i].data(), 2, idx, d2);
    nearest.push_back(std::sqrt(d2[1]));
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  e.spacing_median = nearest[nearest.size() / 2];
  e.max_gap = max_gap > 0 ? max_gap : 4 * e.spacing_median;

  const std::size_t nv = mesh.num_vertices();
  e.out.assign(nv, 0.0);
  e.in.assign(nv, 0.0);
  e.gap.assign(nv, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::uint32_t> idx(k);
    std::vector<double> d2(k);
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      const std::size_t found = tree.knnSearch(mesh.vertices[v].data(), std::size_t(k), idx.data(), d2.data());
      e.gap[v] = std::sqrt(d2[0]);
      for (std::size_t j = 0; j < found; ++j) {
        e.out[v] = std::max(e.out[v], e.residual[idx[j]]);
        e.in[v] = std::max(e.in[v], -e.residual[idx[j]]);
      }
    }
  });
  for (double g : e.gap) e.unsupported += g > e.max_gap;

  // Each vertex moves along its normal far enough that the plane of every face around it moves
  // by the full amount: by 1 / min_f (n_f . n_v), at most 2 (a cube's edge: sqrt 2, its corner:
  // sqrt 3, which makes the outer mesh of a cube the cube grown by that amount on every side).
  const std::vector<Eigen::Vector3d> n = vertex_normals(mesh);
  const FaceGeometry g = face_geometry(mesh);
  std::vector<double> least_cos(nv, 1.0);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) {
      const std::uint32_t v = mesh.face(f)[c];
      if (g.area[f] > 0) least_cos[v] = std::min(least_cos[v], g.normal[f].dot(n[v]));
    }
  // Where the mesh bends, the part may bend sharper between its points: an edge or a corner a
  // point spacing s from the nearest points sticks out of (or into) the mesh between them by up to
  // about s sin(theta), theta the largest angle between n_v and the faces within 3 s of v (a
  // reconstruction rounds a corner over several faces, so the faces around v alone see too little).
  {
    PointsAdaptor<Eigen::Vector3d> centroids{g.centroid};
    KdTree<Eigen::Vector3d, 3> faces(3, centroids, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    faces.buildIndex();
    const double reach = 3 * e.spacing_median;
    std::vector<double> bend(nv, 0.0);
    // With exact feature edges: the faces within reach on v's side of them (a walk across the
    // other edges), none for a vertex on one.
    const bool sides = exact_feature_edges && !mesh.feature_edges.empty();
    const MeshEdges edges = sides ? mesh_edges(mesh) : MeshEdges();
    const VertexFaces around = sides ? vertex_faces(mesh) : VertexFaces();
    std::vector<char> feature(sides ? edges.size() : 0, 0), on_feature(sides ? nv : 0, 0);
    for (const auto& fe : mesh.feature_edges)
      if (sides)
        if (const auto e = edges.find(fe[0], fe[1])) feature[*e] = 1, on_feature[fe[0]] = on_feature[fe[1]] = 1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<std::pair<std::uint32_t, double>> hits;
      std::vector<std::uint32_t> stack, seen;
      for (std::size_t v = r.begin(); v < r.end(); ++v) {
        double c = least_cos[v];
        if (!sides) {
          faces.radiusSearch(mesh.vertices[v].data(), reach * reach, hits, nanoflann::SearchParams(32, 0, false));
          for (const auto& [f, d2] : hits)
            if (g.area[f] > 0) c = std::min(c, g.normal[f].dot(n[v]));
        } else if (on_feature[v]) {
          c = 1;
        } else {
          stack.assign(around.faces(v), around.faces(v) + around.count(v));
          seen = stack;
          while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            if (g.area[f] > 0) c = std::min(c, g.normal[f].dot(n[v]));
            for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
              const std::uint32_t e = edges.face_edge[mesh.face_start[f] + k];
              if (feature[e]) continue;
              for (std::size_t j = 0; j < edges.faces_on(e); ++j) {
                const std::uint32_t h = edges.faces(e)[j];
                if ((g.centroid[h] - mesh.vertices[v]).squaredNorm() > reach * reach ||
                    std::find(seen.begin(), seen.end(), h) != seen.end())
                  continue;
                seen.push_back(h);
                stack.push_back(h);
              }
            }
          }
        }
        c = std::clamp(c, 0.0, 1.0);  // beyond 90 degrees: s at most
        bend[v] = bend_spacings * e.spacing_median * std::sqrt(1 - c * c);
      }
    });
    for (std::size_t v = 0; v < nv; ++v) {
      e.bend_allowance_max = std::max(e.bend_allowance_max, bend[v]);
      e.out[v] += bend[v];
      e.in[v] += bend[v];
    }
  }
  e.outer = mesh;
  e.inner = mesh;
  e.outer.normals.clear();
  e.inner.normals.clear();
  for (std::size_t v = 0; v < nv; ++v) {
    const double stretch = 1 / std::max(0.5, least_cos[v]);
    e.outer.vertices[v] = mesh.vertices[v] + stretch * e.out[v] * n[v];
    e.inner.vertices[v] = mesh.vertices[v] - stretch * e.in[v] * n[v];
  }
  // What the two meshes leave out: points outside the outer mesh or inside the inner one. (Moving
  // corners further after them was tried: where the outer mesh folds over itself, inside and
  // outside lose their meaning and the moves ran away, to 1.3 mm on the domed block's corners.)
  {
    const MeshDistance outer_distance(e.outer), inner_distance(e.inner);
    std::vector<double> excess(points.size(), 0.0);
    tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
      excess[i] = std::max({0.0, outer_distance.signed_distance(points[i]), -inner_distance.signed_distance(points[i])});
    });
    for (double x : excess)
      if (x > 1e-6) ++e.points_beyond, e.beyond_max = std::max(e.beyond_max, x);
  }
  return e;
}

}  // namespace scallop
