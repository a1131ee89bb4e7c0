// The paper's segmentation of a quad mesh into sharp height fields (mesh.segment).
//
// papers/point-clouds-to-workpieces.md, "Optimal surface segmentation for CNC": a sharp height
// field (SHF) is a quad patch with no extraordinary point (EP: an interior vertex whose valence
// is not 4) inside it and the sharp features on its border. The patches are the regions between
// clipping edges, set in the paper's order of priority:
//   1. the minimum spanning tree (Kruskal) of the weighted graph of the EPs: its vertices the EPs
//      and the auxiliary vertices where two connection lines cross, its edges the pieces of the
//      connection lines (straight quad-edge lines from an EP to another EP; lines crossing a
//      sharp edge that is on no connection line are dropped), weighted by eq. (4): the sum of
//      SC * length over the piece's mesh edges (SC = 0.1 on sharp edges, 1 elsewhere), times
//      AC = 1000 between two auxiliary vertices, NC = 0.1 for an NF piece (both ends EPs, and one
//      of the four mesh edges beside it at its ends starts no connection line);
//   2. sharp edges (dihedral angle over theta) and the mesh's boundary;
//   3. the NF pieces;
//   4. sharp features (any clipping chain) ending inside the mesh, extended straight on until
//      they meet another clipping edge;
//   5. the EPs' remaining quad-edge lines, each traced straight until it meets a clipping edge.
// The paper stops there. What it leaves implicit is made explicit, each a further cut recorded
// with its own priority:
//   6. a region that is not a rectangle of the quad grid (a concave corner where a line ended,
//      a ring around a cylinder) is cut straight on from its concave corner, or across the ring,
//      until every region is a rectangle (the B-spline fit needs a grid);
//   7. a rectangle that is not a height field along any direction (the smallest n . d over its
//      faces not above min_normal_dot for the best d) is halved across its longer side until
//      every part is (a single quad is one, along its own normal, so the halving ends).
// Then, unless join is off, neighbouring rectangles that share a whole side with no sharp edge on
// it are joined while their union is a height field with every n . d above join_min_normal_dot
// and the union's border runs on through the shared side's ends turning by at most 30 degrees
// (two patches whose corner is an extraordinary point would otherwise make a border that bends
// there, and the B-spline fitted to it folds over), the best union first (the paper lets the
// number of patches be controlled; the lines of priorities 4-6 cut more than the sharp edges and
// EPs need). Joined patches keep the SHF's
// conditions: the shared side's inner vertices had two faces on either side, so they are regular.
// Each patch's direction d maximises the smallest n . d over its faces' unit normals (the axis
// of the smallest cap holding them, by 400 Badoiu-Clarkson steps on the normals: within about
// 1e-3 of the best smallest n . d; the reported smallest n . d is exact for the d returned).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "nodes/types/segments.h"

namespace scallop {

struct SegmentOptions {
  double sharp_angle_deg = 50;    // theta: an edge is sharp when its faces' normals differ more
  double min_normal_dot = 0.05;   // a patch is a height field along d when every n . d exceeds this
  double sharp_coefficient = 0.1;  // SC on sharp edges
  double nf_coefficient = 0.1;     // NC
  double auxiliary_coefficient = 1000;  // AC
  bool join = true;                     // join neighbouring rectangles (see above)
  double join_min_normal_dot = 0.5;     // ... while the union's smallest n . d stays above this
};

// What the segmentation did, for the report.
struct SegmentStats {
  std::size_t extraordinary_points = 0;
  std::size_t sharp_edges = 0;
  std::size_t connection_lines = 0;          // EP to EP lines kept
  std::size_t dropped_connection_lines = 0;  // crossing a priori sharp edge
  std::size_t auxiliary_vertices = 0;
  std::size_t graph_edges = 0, mst_edges = 0, nf_edges = 0;
  std::array<std::size_t, 8> clipping_by_priority{};  // mesh edges first set at priority 1..7
  std::size_t height_field_splits = 0;
  std::size_t joins = 0;  // pairs of neighbouring patches joined
};

// mesh      a manifold quad mesh, faces counter-clockwise seen from outside (every face 4
//           corners); its face_label and feature_edges are ignored and replaced.
// progress  optional, called with a fraction in [0, 1] and what is being done.
// Returns the segments: the mesh with face_label = patch and feature_edges = its sharp edges;
// per patch its grid, faces, direction and smallest n . d; the clipping edges. clipping_priority
// (when given) receives the priority (1..7) of each clipping edge, in the order of
// Segments::clipping_edges.
// Throws std::invalid_argument naming the first face that is not a quad, a non-manifold edge, or
// a non-finite vertex; std::runtime_error if a region cannot be cut into rectangles.
Segments segment_shf(const Mesh& mesh, const SegmentOptions& options, SegmentStats* stats = nullptr,
                     std::vector<std::uint8_t>* clipping_priority = nullptr,
                     const std::function<void(double, const std::string&)>& progress = {});

// A direction d nearly maximising min_i n_i . d over unit vectors n_i (the axis of the smallest
// spherical cap holding them, to about 1e-3 in the minimum), and that minimum for this d. Zero normals are skipped; all zero -> (+z, 1).
std::pair<Eigen::Vector3d, double> best_height_field_direction(const std::vector<Eigen::Vector3d>& normals);

}  // namespace scallop
