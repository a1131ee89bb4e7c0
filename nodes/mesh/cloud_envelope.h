// How far the real part may lie off a mesh made from its point cloud, and the two meshes that
// bound it: the mesh pushed out by that much (what the balls are kept off, and gouge is measured
// against) and pushed in (what scallop is measured from). A reconstruction bevels sharp edges and
// smooths noise; the programs and their certificate must answer to the part, not to the mesh.
//
// For each vertex v, with d_i the signed distances (positive outside) of the cloud's k points
// nearest to v from the mesh:
//   out_v = max(0, max_i d_i) + c sigma_v   the farthest a point near v lies outside the mesh
//   in_v  = max(0, max_i -d_i) + c sigma_v  the farthest one lies inside
// sigma_v the standard deviation of the d_i about their mean (the noise; 0 where the mesh interpolates
// the points), c the `spread`: the largest of 16 noisy deviations reaches only about 1.8 sigma_v above
// their mean, and where the noise hides the part's shape it may stand above that (the fandisk x 50's
// cloud at sigma 0.02: a 22.6 degree edge, milder than the sharp angle and rounded by the
// denoising, 0.053 mm above the mesh, whose nearest points lie 0.18 mm and more off its apex).
// Both grow by the bend allowance: s sin(theta_v), s the median point spacing, theta_v the largest
// angle between v's normal and the faces within 3 s of v: an edge or a corner of the part between
// its points may stick out of the mesh by about that much (with exact_feature_edges, below, the
// crease a face may hide instead); and at the corners of a face that bridges a wider gap g in the
// cloud (the farthest its centroid and edge midpoints lie from every point), at least
// g min(1, tan phi_f), phi_f the largest angle between the face and its neighbours: the part may
// bend anywhere in the gap (out_v for the neighbours below the face's plane, a crest; in_v for
// those above, a valley; not with exact_feature_edges, whose crease counts the gap). The outer
// mesh moves v along its normal until the plane of every face around v has moved by out_v (v
// moves at most 2 out_v), the inner by in_v inward. The points the two meshes still leave out
// (a fold of the mesh) are counted, with the farthest. Where the cloud samples
// the part densely and its noise is bounded by what k points show, the part lies between the two
// (a bevelled edge: the points at the true edge lie outside the bevel by its depth; noise: the
// largest of k deviations, about 2-3 sigma for k = 16). Vertices farther than `max_gap` from every
// point (a hole the repair filled) are unsupported: counted and reported, their bounds only those
// of the points nearest them.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

struct CloudEnvelope {
  Mesh outer, inner;               // the mesh's faces at V + s out N and V - s in N (N: vertex normals, s: stretch)
  std::vector<double> out, in;     // #V (mm)
  std::vector<double> residual;    // #P signed distances of the points from the mesh (mm, + outside)
  std::vector<double> gap;         // #V distance from each vertex to its nearest point (mm)
  double spacing_median = 0;       // median distance from a point to its nearest other point (mm)
  double max_gap = 0;              // the gap above which a vertex is unsupported (mm)
  std::size_t unsupported = 0;     // vertices with gap > max_gap
  double bend_allowance_max = 0;   // the largest bend allowance added (mm)
  std::size_t points_beyond = 0;   // points farther than 1e-6 mm outside the outer mesh or inside the inner one
  double beyond_max = 0;           // the farthest of them (mm)
  std::size_t vertices_checked = 0;  // with exact feature edges: vertices on one or at no point, bounded by their points' surfaces
  double off_points_max = 0;       // the largest bound one of them got that way (mm)
  std::size_t vertices_without_surface = 0;  // of those, where a face's points fit no surface: the bend allowance instead
};

// mesh    faces outward (corners counter-clockwise seen from outside), any polygons; closed for a
//         trustworthy inside/outside at edges (MeshDistance::signed_distance).
// points  #P >= k the cloud the mesh was made from (mm).
// k       points per vertex; max_gap  0: 4 times the median point spacing.
// bend    the bend allowance's factor: s and g above are bend times the spacing and gap (1; less on a
//         mesh whose edges were restored by mesh.sharpen, which no longer bevels them).
// exact_feature_edges  the mesh's feature edges are the part's own (mesh.sharpen's restored
//         edges), its other vertices points of the part: the allowance is instead the crease each
//         face may hide between its corners, bend * l_f / 2 * tan(T_f / 2) (T_f the largest angle
//         between two of the face and the faces sharing a corner with it: those below its plane for
//         out, a crest; above it for in, a valley; l_f its longest edge, at most twice the larger of
//         s and the gap g_f it bridges), each vertex the largest of its faces'; faces with a corner on a feature edge are left out
//         (those corners are bounded below, and a face's tilt through them with them), and a vertex
//         on a feature edge gets none from its own faces (a corner at no point off the edges is bounded
//         below too, and still gets its faces' allowance, which also reaches their other corners). Where the points over a face and a
//         spacing around it fit one local surface (quadric, largest residual m at most a quarter
//         spacing, the face bridging no gap wider than twice their own spacing), the face's
//         allowance is at most that surface's height over the face's plane (1.1 times the largest
//         on a grid of sixths of the face; out where it stands above, in where below) plus 3 m:
//         a random cloud's faces turn against each other far more than a smooth part bends.
//         Where two planes meeting in a line fit those points better (CreaseSurface, seeded by the
//         two faces around that turn most; a smaller largest residual), their height over the face
//         (exact) plus 3 of their misfits it is instead: a crease softer than the feature edges, as
//         between a CAD mesh's facets, which a quadric misses by the turn times the points' spread
//         and whose crest its bulge falls short of.
//         Instead, a vertex at no point of the cloud (farther than 1e-6 mm from every one: where
//         mesh.sharpen extrapolated local surfaces to meet at an edge or a corner; off a feature
//         edge and within a quarter spacing of a point, as where mesh.repair collapsed a sliver,
//         that distance bounds it both ways instead) is measured against each face of the part
//         around it (the faces reached from its own across the other edges without leaving the
//         points' search radius): the local surface (quadric) of that face's points nearest it
//         (the first of 6, 12, 24 or 48 spacings holding 20; a point on the face nearest it), its
//         height h above that surface and the fit's largest residual m give
//         out_v >= max(0, -h) + 3 m, in_v >= max(0, h) + 3 m (the residual counts the shape the
//         quadric misses, facets or curvature, as cloud.height_field's model does). Where a face's points make no surface (fewer than 10 within 48 spacings, or
//         a misfit above a quarter spacing: points of two faces across an edge not flagged, or a
//         face curved too tightly for a quadric, whose three misfits fold the outer mesh), the vertex
//         gets the bend allowance (as without exact feature edges) instead. On the domed block's
//         200 000-point cloud (seed 3) the quadric over the top's 1 mm facets put the corner
//         (0, 40, 15) 0.005 mm low, while every point near it lay on the mesh.
// spread  c above (0: the largest deviation alone).
// Throws std::invalid_argument for a mesh without faces, fewer than k points, k < 1, a non-finite
// point, max_gap < 0, bend < 0 or spread < 0.
CloudEnvelope cloud_envelope(const Mesh& mesh, const std::vector<Eigen::Vector3d>& points, int k, double max_gap = 0,
                             double bend = 1, bool exact_feature_edges = false, double spread = 0);

}  // namespace scallop
