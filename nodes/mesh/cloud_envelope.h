// How far the real part may lie off a mesh made from its point cloud, and the two meshes that
// bound it: the mesh pushed out by that much (what the balls are kept off, and gouge is measured
// against) and pushed in (what scallop is measured from). A reconstruction bevels sharp edges and
// smooths noise; the programs and their certificate must answer to the part, not to the mesh.
//
// For each vertex v, with d_i the signed distances (positive outside) of the cloud's k points
// nearest to v from the mesh:
//   out_v = max(0, max_i d_i)   the farthest a point near v lies outside the mesh
//   in_v  = max(0, max_i -d_i)  the farthest one lies inside
// Both grow by s sin(theta_v), s the median point spacing, theta_v the largest angle between v's
// normal and the faces within 3 s of v: an edge or a corner of the part between its points may
// stick out of the mesh by about that much. The outer
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
  double bend_allowance_max = 0;   // the largest s sin(theta_v) added (mm)
  std::size_t points_beyond = 0;   // points farther than 1e-6 mm outside the outer mesh or inside the inner one
  double beyond_max = 0;           // the farthest of them (mm)
};

// mesh    faces outward (corners counter-clockwise seen from outside), any polygons; closed for a
//         trustworthy inside/outside at edges (MeshDistance::signed_distance).
// points  #P >= k the cloud the mesh was made from (mm).
// k       points per vertex; max_gap  0: 4 times the median point spacing.
// bend    the bend allowance in spacings: s above is bend times the median spacing (1; less on a
//         mesh whose edges were restored by mesh.sharpen, which no longer bevels them).
// exact_feature_edges  the mesh's feature edges are the part's own (mesh.sharpen's restored
//         edges): the allowance looks only at the faces on a vertex's side of them (reached
//         without crossing one), and a vertex on one gets none; elsewhere (a chamfer left) as above.
// Throws std::invalid_argument for a mesh without faces, fewer than k points, k < 1, a non-finite
// point, max_gap < 0 or bend < 0.
CloudEnvelope cloud_envelope(const Mesh& mesh, const std::vector<Eigen::Vector3d>& points, int k, double max_gap = 0,
                             double bend = 1, bool exact_feature_edges = false);

}  // namespace scallop
