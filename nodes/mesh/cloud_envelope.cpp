#include "nodes/mesh/cloud_envelope.h"

#include "nodes/mesh/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>

#include "nodes/geom/crease_surface.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/local_surface.h"
#include "nodes/geom/segment.h"
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
constexpr double kFlat = 1e-3;       // mm: a face allowance this small is not worth a local surface
constexpr double kNearPoint = 0.25;   // spacings: a vertex off a feature edge this near a point is bounded by that distance

// The largest distance of the points from the surface along its normal.
double largest_residual(const LocalSurface& surface, const std::vector<Eigen::Vector3d>& points) {
  double misfit = 0;
  for (const auto& p : points) misfit = std::max(misfit, std::abs(surface.value(p)));
  return misfit;
}

// How far the part stands above (first) and below (second) face f's plane within the face, its
// largest height on a grid of sixths of each triangle of the face's fan. part_above(x): how far
// the part stands above x along the face's outward normal (negative: below).
template <class PartAbove>
std::pair<double, double> bulge_over_face(const Mesh& mesh, std::size_t f, PartAbove&& part_above) {
  double above = 0, below = 0;
  const std::uint32_t* corner = mesh.face(f);
  for (std::size_t k = 1; k + 1 < mesh.face_size(f); ++k)
    for (int i = 0; i <= 6; ++i)
      for (int j = 0; i + j <= 6; ++j) {
        const Eigen::Vector3d x = mesh.vertices[corner[0]] +
                                  (i / 6.0) * (mesh.vertices[corner[k]] - mesh.vertices[corner[0]]) +
                                  (j / 6.0) * (mesh.vertices[corner[k + 1]] - mesh.vertices[corner[0]]);
        const double height = part_above(x);
        above = std::max(above, height);
        below = std::max(below, -height);
      }
  return {above, below};
}

// The same for two planes meeting in a line, exact (CreaseSurface::extremes_over on each triangle
// of the face's fan): a grid misses the crease's peak between its points by up to half its step
// times the turn (0.023 mm across a 2 mm face at 7.9 degrees).
std::pair<double, double> crease_over_face(const Mesh& mesh, std::size_t f, const CreaseSurface& crease) {
  double above = 0, below = 0;
  const std::uint32_t* corner = mesh.face(f);
  for (std::size_t k = 1; k + 1 < mesh.face_size(f); ++k) {
    const auto [up, down] =
        crease.extremes_over(mesh.vertices[corner[0]], mesh.vertices[corner[k]], mesh.vertices[corner[k + 1]]);
    above = std::max(above, up);
    below = std::max(below, down);
  }
  return {above, below};
}
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
  // Every point also bounds the corners of the face it lies nearest: a large face (a hole's
  // filling) has points over its middle that are among no corner's k nearest, and the outer mesh
  // would pass under them. (The nearest face and its nearest point serve the feature edges below.)
  std::vector<std::uint32_t> nearest_face(points.size());
  std::vector<Eigen::Vector3d> nearest_at(points.size());
  tbb::parallel_for(std::size_t(0), points.size(),
                    [&](std::size_t i) { nearest_face[i] = std::uint32_t(distance.closest_face(points[i], nearest_at[i])); });
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t c = 0, m = mesh.face_size(nearest_face[i]); c < m; ++c) {
      const std::uint32_t v = mesh.face(nearest_face[i])[c];
      e.out[v] = std::max(e.out[v], e.residual[i]);
      e.in[v] = std::max(e.in[v], -e.residual[i]);
    }

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
    // The least cosine between v's normal and the faces within reach (hits: room for the search).
    const auto least_cos_within_reach = [&](std::size_t v, std::vector<std::pair<std::uint32_t, double>>& hits) {
      double c = least_cos[v];
      faces.radiusSearch(mesh.vertices[v].data(), reach * reach, hits, nanoflann::SearchParams(32, 0, false));
      for (const auto& [f, d2] : hits)
        if (g.area[f] > 0) c = std::min(c, g.normal[f].dot(n[v]));
      return c;
    };
    // With exact feature edges: the crease each face may hide (below), none for a vertex on one.
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
    // A face with a corner on a feature edge: the faces around that corner lie on both sides of
    // the edge, whose turn is no crease inside the face; its tilt through that corner is counted
    // there (below). A face whose corner is only at no point keeps its crease: that corner's own
    // bound holds it alone, not the face's other corners (the block x 5's cloud: 7 samples of the
    // true block up to 0.0265 mm outside the outer mesh, beside unflagged creases of 18 to 40
    // degrees, when such faces were left out).
    const auto on_an_edge = [&](std::uint32_t f) {
      for (std::size_t k = 0; sides && k < mesh.face_size(f); ++k)
        if (on_feature[mesh.face(f)[k]]) return true;
      return false;
    };
    // Without exact feature edges, the allowance of the faces within reach, the same both ways.
    // With them, the crease a face may hide between its corners: each vertex gets the largest over
    // its faces (crest out, valley in).
    std::vector<double> bend_out(nv, 0.0), bend_in(nv, 0.0);
    if (!sides) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 256), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::pair<std::uint32_t, double>> hits;
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
          const double c = std::clamp(least_cos_within_reach(v, hits), 0.0, 1.0);  // beyond 90 degrees: s at most
          bend_out[v] = bend_in[v] = bend_spacings * e.spacing_median * std::sqrt(1 - c * c);
        }
      });
    } else {
      // The part between a face's corners (points of it) may hold a crease as sharp as the turn the
      // faces around the face show: a crease of angle T crossing a chord of length l stands at most
      // l / 2 tan(T / 2) off it (at its middle). T: the largest angle between two of the face and
      // the faces sharing a corner with it, those below its plane for a crest (out), above for a
      // valley (in); l: the face's longest edge, and at most twice the larger of the spacing and the
      // gap the face bridges (the points on either side of the crease lie that near it). (Its width
      // across the crease, along n_f x (n_a x n_b), left the block x 5's cross bores 0.0115 mm outside
      // the outer mesh where their ridge meets curvature.) On the block x 5's faceted bosses (creases
      // up to 13 degrees, points 0.31 mm apart) the outer mesh's p90 0.072 -> 0.055 mm.
      //
      // Where the points near a face fit one local surface (a quadric, its largest residual m at
      // most a quarter spacing), the part there is that surface within 3 m, and the face's
      // allowance is instead how far that surface stands off the face's plane within the face (the
      // part's curvature between the corners), plus 3 m: on a dense clean cloud of a smooth face
      // the faces of a random triangulation turn 10 degrees and more against each other while the
      // part bends far less (the fandisk's cloud: its outer mesh stood 0.02 mm above the part over
      // the areas its programs left over h = 0.02). A crease the mesh does not have as an edge
      // leaves a misfit, and the crease's allowance above counts there.
      std::vector<double> face_out(mesh.num_faces(), 0.0), face_in(mesh.num_faces(), 0.0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.num_faces(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> below, above;
        std::vector<std::pair<std::uint32_t, double>> hits;
        std::vector<std::uint32_t> idx(kSidePoints);
        std::vector<double> d2(kSidePoints);
        std::vector<Eigen::Vector3d> near;
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
          if (!(g.area[f] > 0) || on_an_edge(std::uint32_t(f))) continue;
          below.assign(1, std::uint32_t(f));
          above.assign(1, std::uint32_t(f));
          double longest = 0;
          for (std::size_t k = 0, m = mesh.face_size(f); k < m; ++k) {
            const std::uint32_t v = mesh.face(f)[k];
            longest = std::max(longest, (mesh.vertices[mesh.face(f)[(k + 1) % m]] - mesh.vertices[v]).norm());
            for (std::size_t j = 0; j < around.count(v); ++j) {
              const std::uint32_t h = around.faces(v)[j];
              if (h == f || !(g.area[h] > 0) || on_an_edge(h)) continue;
              auto& side = g.normal[f].dot(g.centroid[h] - g.centroid[f]) < 0 ? below : above;
              if (std::find(side.begin(), side.end(), h) == side.end()) side.push_back(h);
            }
          }
          const auto crease = [&](const std::vector<std::uint32_t>& faces) {
            double c = 1;  // the least cosine between two of them
            for (std::size_t i = 0; i < faces.size(); ++i)
              for (std::size_t j = i + 1; j < faces.size(); ++j) c = std::min(c, g.normal[faces[i]].dot(g.normal[faces[j]]));
            const double chord = std::min(longest, 2 * std::max(e.spacing_median, face_gap[f]));
            c = std::clamp(c, 0.0, 1.0);  // beyond 90 degrees: as 90, half the chord
            return bend_spacings * chord / 2 * std::sqrt((1 - c) / (1 + c));  // tan(T / 2)
          };
          const double crest = crease(below), valley = crease(above);
          face_out[f] = crest, face_in[f] = valley;
          if (std::max(crest, valley) <= kFlat) continue;  // nothing a surface could lower
          // The points over the whole face and a spacing beyond its edges (a crease along or
          // across it leaves them on two surfaces), kSidePoints at least.
          double around_face = 0;
          for (std::size_t k = 0; k < mesh.face_size(f); ++k)
            around_face = std::max(around_face, (mesh.vertices[mesh.face(f)[k]] - g.centroid[f]).norm());
          around_face += e.spacing_median;
          tree.radiusSearch(g.centroid[f].data(), around_face * around_face, hits, nanoflann::SearchParams(32, 0, false));
          near.clear();
          for (const auto& hit : hits) near.push_back(points[hit.first]);
          double covered = around_face;  // the radius the points were taken within
          if (near.size() < kSidePoints) {
            near.clear();
            const std::size_t found = tree.knnSearch(g.centroid[f].data(), kSidePoints, idx.data(), d2.data());
            for (std::size_t j = 0; j < found; ++j) near.push_back(points[idx[j]]);
            if (found > 0) covered = std::sqrt(d2[found - 1]);
          }
          const std::optional<LocalSurface> surface = fit_local_surface(near);
          double surface_out = INFINITY, surface_in = INFINITY;  // the surface's allowance, where it fits
          double surface_misfit = INFINITY;
          // Not over a hole in the sampling (a gap wider than twice the spacing of the points
          // around, sqrt(pi a^2 / N) for the N points within a): there the part is not known to
          // follow them. The spacing is the local one: CAD-sampled clouds are sparser on large
          // flat facets (the fandisk's: 8 points per mm² beside a median of 37).
          const double local_spacing = covered * std::sqrt(std::numbers::pi / double(std::max<std::size_t>(near.size(), 1)));
          if (surface && face_gap[f] <= 2 * local_spacing) {
            const double misfit = largest_residual(*surface, near);
            if (misfit <= kMostMisfit * e.spacing_median) {
              // x's height over the surface is outward * value(x): the part stands above x by minus
              // that. A tenth more for where it rises between the grid's points (on a jittered
              // cylinder a grid of thirds without it left the outer mesh 0.0004 mm inside the part).
              const double outward = surface->normal.dot(g.normal[f]) < 0 ? -1 : 1;
              const auto [above_plane, below_plane] =
                  bulge_over_face(mesh, f, [&](const Eigen::Vector3d& x) { return -outward * surface->value(x); });
              surface_out = 1.1 * bend_spacings * above_plane + kMisfits * misfit;
              surface_in = 1.1 * bend_spacings * below_plane + kMisfits * misfit;
              surface_misfit = misfit;
            }
            // A crease softer than the feature edges (a CAD mesh's facets) between two of the faces
            // around: two planes fit its points where a quadric misses them (on the fandisk's cloud
            // by 0.01 mm, three times that in the allowance), seeded by the two faces that turn most.
            // The better fit of the two decides: a quadric smooths the crease the planes fit, and its
            // bulge falls short of the crest (the block x 5's faceted bosses: 0.048 mm, 3 misfits
            // included, over a face the 7.9 degree crease stands 0.057 mm above).
            std::array<std::uint32_t, 2> most{std::uint32_t(f), std::uint32_t(f)};
            double least_cos = 2;
            for (const auto* side : {&below, &above})
              for (const std::uint32_t a : *side)
                for (const auto* other : {&below, &above})
                  for (const std::uint32_t b : *other)
                    if (const double c = g.normal[a].dot(g.normal[b]); c < least_cos) least_cos = c, most = {a, b};
            const std::optional<CreaseSurface> crease_surface =
                fit_crease_surface(near, g.normal[f], {g.normal[most[0]], g.normal[most[1]]});
            if (crease_surface && crease_surface->misfit <= kMostMisfit * e.spacing_median &&
                crease_surface->misfit < surface_misfit) {
              const auto [above_plane, below_plane] = crease_over_face(mesh, f, *crease_surface);
              surface_out = bend_spacings * above_plane + kMisfits * crease_surface->misfit;
              surface_in = bend_spacings * below_plane + kMisfits * crease_surface->misfit;
            }
          }
          face_out[f] = std::min(crest, surface_out);
          face_in[f] = std::min(valley, surface_in);
        }
      });
      for (std::size_t f = 0; f < mesh.num_faces(); ++f)
        for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
          const std::uint32_t v = mesh.face(f)[k];
          if (on_feature[v]) continue;
          bend_out[v] = std::max(bend_out[v], face_out[f]);
          bend_in[v] = std::max(bend_in[v], face_in[f]);
        }
    }
    // Without exact feature edges, a face bridging a hole in the sampling wider than the spacing:
    // the part may bend anywhere between its corners, as much as the face bends against its
    // neighbours (across its edges that are not feature edges: a bend the mesh has as an edge is the
    // allowance's above): up to the gap times the tangent of that angle (at most the gap), out of
    // the mesh where a neighbour bends away below the face's plane (a crest), into it where one
    // bends up (a valley). The fandisk cloud's mesh had a 0.95 mm face over a hole 0.34 mm from
    // every point, between faces 6 degrees from it on facets of the part: their edge stood 0.035 mm
    // out of it, and the spacing's allowance was 0.009 there. With exact feature edges the crease
    // above counts the gap (its chord); this rule would count it on most faces of a random cloud,
    // whose triangles' edges are longer than the nearest-point spacing (the block x 5's: 75 % of
    // the faces have a gap above it, median 0.43 mm for a spacing of 0.31).
    std::vector<double> gap_out(nv, 0.0), gap_in(nv, 0.0);
    for (std::size_t f = 0; !sides && f < mesh.num_faces(); ++f) {
      if (!(face_gap[f] > e.spacing_median) || !(g.area[f] > 0)) continue;
      double crest = 1, valley = 1;  // the least cosines to the neighbours below and above the face's plane
      for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
        const std::uint32_t edge = edges.face_edge[mesh.face_start[f] + k];
        if (feature[edge]) continue;
        for (std::size_t j = 0; j < edges.faces_on(edge); ++j)
          if (const std::uint32_t h = edges.faces(edge)[j]; h != f && g.area[h] > 0) {
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
    // around it: the faces reached from v's across the other edges without leaving the points'
    // search radius (a point on the face nearest it; none that lies on a feature edge, which belongs
    // to either face). Reached within the radius, not joined over the whole mesh: where a feature
    // edge's line breaks off anywhere, two faces of the part are one there, and the points of both
    // fit no surface (the block x 5's cloud: 3 131 of 7 286 such vertices, along whole edges).
    if (sides) {
      constexpr std::uint32_t kEitherFace = std::numeric_limits<std::uint32_t>::max();
      std::vector<std::uint32_t> face_of_point(points.size());
      tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
        const Eigen::Vector3d& q = nearest_at[i];
        const std::uint32_t f = nearest_face[i];
        face_of_point[i] = f;
        const std::uint32_t* corner = mesh.face(f);
        for (std::size_t k = 0, m = mesh.face_size(f); k < m; ++k) {
          const Eigen::Vector3d &a = mesh.vertices[corner[k]], &b = mesh.vertices[corner[(k + 1) % m]];
          // (on a corner that lies on a feature edge too: the search may return any face around
          // that corner, one of them with no feature edge of its own, and which one it returned
          // differed between two machines: a point on the corner then counted on a face beside it)
          if ((feature[edges.face_edge[mesh.face_start[f] + k]] && segment_distance(q, a, b) <= kAtPoint) ||
              (on_feature[corner[k]] && (q - a).norm() <= kAtPoint))
            face_of_point[i] = kEitherFace;
        }
      });
      std::vector<double> off_out(nv, 0.0), off_in(nv, 0.0);
      std::vector<double> side_cos(nv, 1.0);
      std::vector<std::uint8_t> no_surface(nv, 0);
      struct Reached {
        std::vector<std::uint32_t> face;
        std::uint32_t round = 0;
      };
      tbb::enumerable_thread_specific<Reached> reached_here;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::pair<std::uint32_t, double>> hits;
        std::vector<Eigen::Vector3d> side_points;
        // The faces reached from `start` across non-feature edges with their centroid within
        // `radius` of x: reached[f] == round.
        Reached& mine = reached_here.local();
        if (mine.face.empty()) mine.face.assign(mesh.num_faces(), 0);
        std::vector<std::uint32_t>& reached = mine.face;
        std::uint32_t& round = mine.round;
        std::vector<std::uint32_t> stack;
        const auto reach_faces = [&](std::uint32_t start, const Eigen::Vector3d& x, double radius) {
          ++round;
          reached[start] = round;
          stack.assign(1, start);
          while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            for (std::size_t k = 0; k < mesh.face_size(f); ++k) {
              const std::uint32_t edge = edges.face_edge[mesh.face_start[f] + k];
              if (feature[edge]) continue;
              for (std::size_t j = 0; j < edges.faces_on(edge); ++j)
                if (const std::uint32_t h = edges.faces(edge)[j];
                    reached[h] != round && (g.centroid[h] - x).squaredNorm() <= radius * radius) {
                  reached[h] = round;
                  stack.push_back(h);
                }
            }
          }
        };
        std::vector<std::uint32_t> side_faces;    // the faces of a side's points
        std::vector<std::uint32_t> faces_around;  // v's own faces on that side
        // The vertex v against two planes meeting in a line fit to a side's points (kSidePoints at
        // least), seen along v's normal: seeded by the side's own facing and the face of its points
        // that turns most from it. False where they do not fit within kMostMisfit spacings (or a
        // plane turns more than 60 degrees from the normal), or stand above one of own_faces (v's
        // faces on that side).
        const auto bound_by_crease = [&](std::size_t v, const Eigen::Vector3d& facing, const std::vector<Eigen::Vector3d>& pts,
                                         const std::vector<std::uint32_t>& faces_of_pts,
                                         const std::vector<std::uint32_t>& own_faces) {
          if (!(facing.norm() > 0) || pts.size() < kSidePoints) return false;
          const Eigen::Vector3d own = facing.normalized();
          Eigen::Vector3d turned = own;
          for (const std::uint32_t f : faces_of_pts)
            if (g.area[f] > 0 && g.normal[f].dot(own) < turned.dot(own)) turned = g.normal[f];
          const std::optional<CreaseSurface> crease = fit_crease_surface(pts, n[v], {own, turned});
          if (!crease || crease->misfit > kMostMisfit * e.spacing_median) return false;
          // Only where the mesh's faces around v follow the two planes (the edge is in the mesh,
          // its flags broken off): a face that cuts across their line (a bevel) leaves the part
          // outside it between its corners, which v's bound alone does not cover (the block x 5's
          // cloud: 3 samples of the true block 0.03 mm outside the outer mesh beside a bevel).
          for (const std::uint32_t f : own_faces)
            if (crease_over_face(mesh, f, *crease).first > kAtPoint) return false;
          // how far the part stands above v along its normal (positive: outside the mesh)
          const double above = crease->height(mesh.vertices[v]);
          side_cos[v] = std::min({side_cos[v], crease->normal[0].dot(n[v]), crease->normal[1].dot(n[v])});
          off_out[v] = std::max(off_out[v], std::max(0.0, above) + kMisfits * crease->misfit);
          off_in[v] = std::max(off_in[v], std::max(0.0, -above) + kMisfits * crease->misfit);
          return true;
        };
        constexpr std::uint32_t kNoSide = std::numeric_limits<std::uint32_t>::max();
        std::vector<std::uint32_t> side_start;  // one face of v's on each side
        std::vector<std::uint32_t> side_of;     // #around(v): which of them
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
          if (!bounded[v]) continue;
          // Off a feature edge and this near a point of the part (where mesh.repair collapsed a
          // sliver's edge): the part passes that near. The quadric of the points up to 6 spacings
          // around, 3 times its misfit, had moved such vertices 0.06 mm out beside the fandisk's soft
          // edges, where its programs left more than h = 0.02.
          if (!on_feature[v] && e.gap[v] <= kNearPoint * e.spacing_median) {
            off_out[v] = off_in[v] = e.gap[v];
            continue;
          }
          const Eigen::Vector3d& x = mesh.vertices[v];
          side_start.clear();
          side_of.assign(around.count(v), kNoSide);
          for (std::size_t j = 0; j < around.count(v); ++j) {
            if (side_of[j] != kNoSide) continue;
            reach_faces(around.faces(v)[j], x, 2 * reach);
            for (std::size_t i = j; i < around.count(v); ++i)
              if (reached[around.faces(v)[i]] == round) side_of[i] = std::uint32_t(side_start.size());
            side_start.push_back(around.faces(v)[j]);
          }
          for (std::size_t side = 0; side < side_start.size(); ++side) {
            Eigen::Vector3d facing = Eigen::Vector3d::Zero();
            for (std::size_t j = 0; j < around.count(v); ++j)
              if (side_of[j] == side) facing += g.area[around.faces(v)[j]] * g.normal[around.faces(v)[j]];
            // The points of this face of the part near v: the first of 6, 12, 24 or 48 spacings
            // that holds kSidePoints of them.
            side_points.clear();
            for (double radius = 2 * reach; radius <= 16 * reach && side_points.size() < kSidePoints; radius *= 2) {
              reach_faces(side_start[side], x, radius);
              tree.radiusSearch(x.data(), radius * radius, hits, nanoflann::SearchParams(32, 0, false));
              side_points.clear();
              for (const auto& [i, d2] : hits)
                if (face_of_point[i] != kEitherFace && reached[face_of_point[i]] == round) side_points.push_back(points[i]);
            }
            side_faces.clear();
            faces_around.clear();
            for (std::size_t j = 0; j < around.count(v); ++j)
              if (side_of[j] == side) faces_around.push_back(around.faces(v)[j]);
            for (const auto& [i, d2] : hits)
              if (face_of_point[i] != kEitherFace && reached[face_of_point[i]] == round) side_faces.push_back(face_of_point[i]);
            const std::optional<LocalSurface> surface = fit_local_surface(side_points);
            // Points of two faces (an edge not flagged, or its line broken off), or a surface curved
            // too tightly for a quadric over them: three misfits of up to a spacing had moved the
            // fandisk cloud's vertices up to 1.1 mm beside neighbours moved 0.05 (259 faces of the
            // outer mesh turned over; 47 so).
            const double misfit = surface ? largest_residual(*surface, side_points) : INFINITY;
            if (misfit > kMostMisfit * e.spacing_median) {
              // Two faces of the part meeting in an edge are two planes meeting in a line: where
              // those fit the points and v's own faces follow them, the vertex is bounded by them as
              // by one face's surface (the ABC plate's 200 000-point cloud: 178 vertices fewer with
              // the spacing's allowance, 0.13 mm out, which holds the balls off a band along edges).
              if (!bound_by_crease(v, facing, side_points, side_faces, faces_around)) no_surface[v] = 1;
              continue;
            }
            const double outward = surface->normal.dot(facing) < 0 ? -1 : 1;
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
          const double allowance = bend_spacings * e.spacing_median * std::sqrt(1 - c * c);
          bend_out[v] = std::max(bend_out[v], allowance);
          bend_in[v] = std::max(bend_in[v], allowance);
        }
        e.off_points_max = std::max({e.off_points_max, off_out[v], off_in[v]});
        least_cos[v] = std::min(least_cos[v], side_cos[v]);
        e.out[v] = std::max(e.out[v], off_out[v]);
        e.in[v] = std::max(e.in[v], off_in[v]);
      }
    }
    for (std::size_t v = 0; v < nv; ++v) {
      e.bend_allowance_max = std::max({e.bend_allowance_max, bend_out[v], bend_in[v], gap_out[v], gap_in[v]});
      e.out[v] += std::max(bend_out[v], gap_out[v]);
      e.in[v] += std::max(bend_in[v], gap_in[v]);
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
