#include "nodes/mesh/cloud_envelope.h"

#include "nodes/mesh/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>

#include "nodes/geom/kd_tree.h"
#include "nodes/geom/local_surface.h"
#include "nodes/geom/segment.h"
#include "nodes/geom/union_find.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_distance.h"

namespace scallop {

namespace {
constexpr double kAtPoint = 1e-6;     // mm: a vertex this near a point is that point
constexpr std::size_t kSidePoints = 2 * kMinSurfacePoints;  // points that make a face's local surface
// The surface's error at a vertex beyond its points, in times the largest residual of the fit (its
// shape bias: the part's facets or curvature the quadric misses), as cloud.height_field's model
constexpr double kMisfits = 3;
constexpr double kMostMisfit = 0.25;  // spacings: a face's local surface missing its points by more fits none
}  // namespace

CloudEnvelope cloud_envelope(const Mesh& mesh, const std::vector<Eigen::Vector3d>& points, int k, double max_gap,
                             double bend_spacings, bool exact_feature_edges, double spread) {
  if (mesh.num_faces() == 0) throw std::invalid_argument("the mesh has no face");
  if (k < 1) throw std::invalid_argument("k must be >= 1");
  if (points.size() < std::size_t(k) || points.size() < 2)
    throw std::invalid_argument("the cloud has " + std::to_string(points.size()) + " points, fewer than k = " +
                                std::to_string(k) + " (and 2)");
  for (const auto& p : points)
    if (!p.allFinite()) throw std::invalid_argument("the cloud has a point that is not finite");
  if (!(max_gap >= 0)) throw std::invalid_argument("max_gap must be >= 0");
  if (!(bend_spacings >= 0)) throw std::invalid_argument("bend must be >= 0");
  if (!(spread >= 0)) throw std::invalid_argument("spread must be >= 0");

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
      double mean = 0, sq = 0;
      for (std::size_t j = 0; j < found; ++j) {
        e.out[v] = std::max(e.out[v], e.residual[idx[j]]);
        e.in[v] = std::max(e.in[v], -e.residual[idx[j]]);
        mean += e.residual[idx[j]];
      }
      mean /= double(found);
      for (std::size_t j = 0; j < found; ++j) sq += (e.residual[idx[j]] - mean) * (e.residual[idx[j]] - mean);
      // The noise's spread: the largest of k deviations reaches only about 1.8 of it above their
      // mean, and the part may stand above that where the noise hides its shape.
      const double noise = spread * std::sqrt(sq / double(found));
      e.out[v] += noise;
      e.in[v] += noise;
    }
  });
  for (double g : e.gap) e.unsupported += g > e.max_gap;

  // Each vertex moves along its normal far enough that the plane of every face around it (and of
  // every face of the part it was measured against, below) moves by the full amount: by
  // 1 / min_f (n_f . n_v), at most 2 (a cube's edge: sqrt 2, its corner: sqrt 3, which makes the
  // outer mesh of a cube the cube grown by that amount on every side).
  const std::vector<Eigen::Vector3d> n = vertex_normals(mesh);
  const FaceGeometry g = face_geometry(mesh);
  std::vector<double> least_cos(nv, 1.0);
  for (std::size_t f = 0; f < mesh.num_faces(); ++f)
    for (std::size_t c = 0; c < mesh.face_size(f); ++c) {
      const std::uint32_t v = mesh.face(f)[c];
      if (g.area[f] > 0) least_cos[v] = std::min(least_cos[v], g.normal[f].dot(n[v]));
    }
  // How wide a hole in the sampling each face bridges: the farthest its centroid and edge midpoints
  // lie from every point.
  std::vector<double> face_gap(mesh.num_faces(), 0.0);
  tbb::parallel_for(std::size_t(0), mesh.num_faces(), [&](std::size_t f) {
    const auto nearest_point = [&](const Eigen::Vector3d& q) {
      std::uint32_t i;
      double d2;
      tree.knnSearch(q.data(), 1, &i, &d2);
      return std::sqrt(d2);
    };
    face_gap[f] = nearest_point(g.centroid[f]);
    for (std::size_t c = 0, m = mesh.face_size(f); c < m; ++c)
      face_gap[f] = std::max(face_gap[f], nearest_point(0.5 * (mesh.vertices[mesh.face(f)[c]] + mesh.vertices[mesh.face(f)[(c + 1) % m]])));
  });
  // Where the mesh bends, the part may bend sharper between its points: an edge or a corner a
  // spacing s from the nearest points sticks out of (or into) the mesh between them by up to
  // about s sin(theta), theta the largest angle between n_v and the faces within 3 spacings of v (a
  // reconstruction rounds a corner over several faces, so the faces around v alone see too little).
  {
    PointsAdaptor<Eigen::Vector3d> centroids{g.centroid};
    KdTree<Eigen::Vector3d, 3> faces(3, centroids, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    faces.buildIndex();
    const double reach = 3 * e.spacing_median;
    std::vector<double> bend(nv, 0.0);
    // The least cosine between v's normal and the faces within reach (hits: room for the search).
    const auto least_cos_within_reach = [&](std::size_t v, std::vector<std::pair<std::uint32_t, double>>& hits) {
      double c = least_cos[v];
      faces.radiusSearch(mesh.vertices[v].data(), reach * reach, hits, nanoflann::SearchParams(32, 0, false));
      for (const auto& [f, d2] : hits)
        if (g.area[f] > 0) c = std::min(c, g.normal[f].dot(n[v]));
      return c;
    };
    // With exact feature edges: the faces within reach on v's side of them (a walk across the
    // other edges), none for a vertex on one.
    const bool sides = exact_feature_edges && !mesh.feature_edges.empty();
    const MeshEdges edges = mesh_edges(mesh);
    const VertexFaces around = sides ? vertex_faces(mesh) : VertexFaces();
    std::vector<char> feature(edges.size(), 0), on_feature(sides ? nv : 0, 0);
    for (const auto& fe : mesh.feature_edges)
      if (const auto e = edges.find(fe[0], fe[1])) {
        feature[*e] = 1;
        if (sides) on_feature[fe[0]] = on_feature[fe[1]] = 1;
      }
    // The vertices the faces' points bound (below): on a feature edge, or at no point.
    std::vector<char> bounded(sides ? nv : 0, 0);
    for (std::size_t v = 0; v < bounded.size(); ++v) bounded[v] = on_feature[v] || e.gap[v] > kAtPoint;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<std::pair<std::uint32_t, double>> hits;
      std::vector<std::uint32_t> stack, seen;
      for (std::size_t v = r.begin(); v < r.end(); ++v) {
        double c = least_cos[v];
        if (!sides) {
          c = least_cos_within_reach(v, hits);
        } else if (on_feature[v]) {
          c = 1;
        } else {
          // A face with a corner the faces' points bound (below) is left out: its tilt through
          // that corner is counted there. So is its tilt of v's normal: v's other faces give it.
          const auto measured = [&](std::uint32_t f) {
            for (std::size_t k = 0; k < mesh.face_size(f); ++k)
              if (bounded[mesh.face(f)[k]]) return true;
            return false;
          };
          stack.assign(around.faces(v), around.faces(v) + around.count(v));
          seen = stack;
          Eigen::Vector3d facing = Eigen::Vector3d::Zero();
          bool beside_measured = false;
          for (const std::uint32_t f : stack)
            if (measured(f)) beside_measured = true;
            else facing += g.area[f] * g.normal[f];
          const Eigen::Vector3d normal = beside_measured && facing.norm() > 0 ? Eigen::Vector3d(facing.normalized()) : n[v];
          c = 1;
          while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            if (g.area[f] > 0 && !measured(f)) c = std::min(c, g.normal[f].dot(normal));
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
    // A face bridging a hole in the sampling wider than the spacing: the part may bend anywhere
    // between its corners, as much as the face bends against its neighbours (across its edges that
    // are not feature edges: a bend the mesh has as an edge is the allowance's above, and with exact
    // ones, leaving out the faces with a corner the faces' points bound): up to the gap times the
    // tangent of that angle (at most the gap), out of
    // the mesh where a neighbour bends away below the face's plane (a crest), into it where one
    // bends up (a valley). The fandisk cloud's mesh had a 0.95 mm face over a hole 0.34 mm from
    // every point, between faces 6 degrees from it on facets of the part: their edge stood 0.035 mm
    // out of it, and the spacing's allowance was 0.009 there.
    const auto corner_bounded = [&](std::uint32_t f) {
      for (std::size_t k = 0; sides && k < mesh.face_size(f); ++k)
        if (bounded[mesh.face(f)[k]]) return true;
      return false;
    };
    std::vector<double> gap_out(nv, 0.0), gap_in(nv, 0.0);
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
      if (!(face_gap[f] > e.spacing_median) || !(g.area[f] > 0) || corner_bounded(f)) continue;
      double crest = 1, valley = 1;  // the least cosines to the neighbours below and above the face's plane
      for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
        const std::uint32_t edge = edges.face_edge[mesh.face_start[f] + k];
        if (feature[edge]) continue;
        for (std::size_t j = 0; j < edges.faces_on(edge); ++j)
          if (const std::uint32_t h = edges.faces(edge)[j]; h != f && g.area[h] > 0 && !corner_bounded(h)) {
            double& c = g.normal[f].dot(g.centroid[h] - g.centroid[f]) < 0 ? crest : valley;
            c = std::min(c, g.normal[f].dot(g.normal[h]));
          }
      }
      const auto allowance = [&](double c) {
        return bend_spacings * face_gap[f] * (c > std::sqrt(0.5) ? std::sqrt(1 - c * c) / c : 1.0);
      };
      for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
        const std::uint32_t v = mesh.face(f)[k];
        gap_out[v] = std::max(gap_out[v], allowance(crest));
        gap_in[v] = std::max(gap_in[v], allowance(valley));
      }
    }
    // With exact feature edges, a vertex on one or at no point (where mesh.sharpen extrapolated local
    // surfaces to meet) against the local surface of the points near it on each face of the part
    // around it (faces joined across the other edges; a point on the face nearest it, none that lies
    // on a feature edge, which belongs to either face).
    if (sides) {
      UnionFind joined(mesh.num_faces());
      for (std::size_t k = 0; k < edges.size(); ++k)
        if (!feature[k])
          for (std::size_t j = 1; j < edges.faces_on(k); ++j) joined.join(edges.faces(k)[0], edges.faces(k)[j]);
      std::vector<std::uint32_t> part_face(mesh.num_faces());
      for (std::size_t f = 0; f < part_face.size(); ++f) part_face[f] = joined.root(std::uint32_t(f));
      constexpr std::uint32_t kEitherFace = std::numeric_limits<std::uint32_t>::max();
      std::vector<std::uint32_t> part_face_of_point(points.size());
      tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
        Eigen::Vector3d q;
        const std::size_t f = distance.closest_face(points[i], q);
        part_face_of_point[i] = part_face[f];
        const std::uint32_t* corner = mesh.face(f);
        for (std::size_t k = 0, m = mesh.face_size(f); k < m; ++k) {
          const Eigen::Vector3d &a = mesh.vertices[corner[k]], &b = mesh.vertices[corner[(k + 1) % m]];
          if (feature[edges.face_edge[mesh.face_start[f] + k]] && segment_distance(q, a, b) <= kAtPoint)
            part_face_of_point[i] = kEitherFace;
        }
      });
      std::vector<double> off_out(nv, 0.0), off_in(nv, 0.0);
      std::vector<double> side_cos(nv, 1.0);
      std::vector<std::uint8_t> no_surface(nv, 0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::pair<std::uint32_t, double>> hits;
        std::vector<std::uint32_t> faces_here;
        std::vector<Eigen::Vector3d> side_points;
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
          if (!bounded[v]) continue;
          faces_here.clear();
          for (std::size_t j = 0; j < around.count(v); ++j) faces_here.push_back(part_face[around.faces(v)[j]]);
          std::sort(faces_here.begin(), faces_here.end());
          faces_here.erase(std::unique(faces_here.begin(), faces_here.end()), faces_here.end());
          for (const std::uint32_t side : faces_here) {
            Eigen::Vector3d facing = Eigen::Vector3d::Zero();
            for (std::size_t j = 0; j < around.count(v); ++j)
              if (const std::uint32_t f = around.faces(v)[j]; part_face[f] == side) facing += g.area[f] * g.normal[f];
            // The points of this face of the part near v: the first of 6, 12, 24 or 48 spacings
            // that holds kSidePoints of them.
            side_points.clear();
            for (double radius = 2 * reach; radius <= 16 * reach && side_points.size() < kSidePoints; radius *= 2) {
              tree.radiusSearch(mesh.vertices[v].data(), radius * radius, hits, nanoflann::SearchParams(32, 0, false));
              side_points.clear();
              for (const auto& [i, d2] : hits)
                if (part_face_of_point[i] == side) side_points.push_back(points[i]);
            }
            const std::optional<LocalSurface> surface = fit_local_surface(side_points);
            if (!surface) {  // too few points, or not on a plane and a quadric over it
              no_surface[v] = 1;
              continue;
            }
            const double outward = surface->normal.dot(facing) < 0 ? -1 : 1;
            double misfit = 0;
            for (const auto& p : side_points) misfit = std::max(misfit, std::abs(surface->value(p)));
            // Points of two faces (an edge not flagged), or a surface curved too tightly for a quadric
            // over them: three misfits of up to a spacing had moved the fandisk cloud's vertices up to
            // 1.1 mm beside neighbours moved 0.05 (259 faces of the outer mesh turned over; 47 so).
            if (misfit > kMostMisfit * e.spacing_median) {
              no_surface[v] = 1;
              continue;
            }
            const double height = outward * surface->value(mesh.vertices[v]);
            side_cos[v] = std::min(side_cos[v], outward * surface->gradient(mesh.vertices[v]).normalized().dot(n[v]));
            off_out[v] = std::max(off_out[v], std::max(0.0, -height) + kMisfits * misfit);
            off_in[v] = std::max(off_in[v], std::max(0.0, height) + kMisfits * misfit);
          }
        }
      });
      for (std::size_t v = 0; v < nv; ++v) {
        e.vertices_checked += bounded[v];
        if (no_surface[v]) {
          // As without exact feature edges: the allowance for the faces within reach.
          ++e.vertices_without_surface;
          std::vector<std::pair<std::uint32_t, double>> hits;
          const double c = std::clamp(least_cos_within_reach(v, hits), 0.0, 1.0);
          bend[v] = std::max(bend[v], bend_spacings * e.spacing_median * std::sqrt(1 - c * c));
        }
        e.off_points_max = std::max({e.off_points_max, off_out[v], off_in[v]});
        least_cos[v] = std::min(least_cos[v], side_cos[v]);
        e.out[v] = std::max(e.out[v], off_out[v]);
        e.in[v] = std::max(e.in[v], off_in[v]);
      }
    }
    for (std::size_t v = 0; v < nv; ++v) {
      e.bend_allowance_max = std::max({e.bend_allowance_max, bend[v], gap_out[v], gap_in[v]});
      e.out[v] += std::max(bend[v], gap_out[v]);
      e.in[v] += std::max(bend[v], gap_in[v]);
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
    const MeshDistance outer_distance(e.outer, &mesh), inner_distance(e.inner, &mesh);
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
