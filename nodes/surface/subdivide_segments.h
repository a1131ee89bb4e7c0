// The patches' quad grids made twice as fine, the new vertices put on the part (surface.fit_bspline).
//
// A B-spline through a patch's quad vertices follows the part only at those vertices: between
// them it can stand off it by far more than a scallop height (the fandisk x 50 from its STL at
// 3000 quads: half of its 59 patches more than 0.29 mm off the part somewhere). The paper refines
// its fit "until the error is under a threshold"; here the data are refined instead of the
// knots: every quad is cut into four (its edges' midpoints and its centroid, Catmull-Clark's
// pattern with straight positions), and each new vertex is moved onto the part
// (snap_to_reference: onto the part's feature curves where it lies on a feature edge, else onto
// its faces), so the fit through the finer grid meets the part there too. Patches that share a
// border get the same new border vertices (one per mesh edge), so their border curves stay one.
#pragma once

#include "nodes/mesh/snap_to_reference.h"
#include "nodes/types/mesh.h"
#include "nodes/types/segments.h"

namespace scallop {

// segments   patches of a mesh of quads (other polygons are cut into as many quads as corners)
// part       the surface the quads were made from, with its feature_edges (at least one face)
// Returns segments with every face cut into four: a rows x cols patch becomes (2 rows - 1) x
// (2 cols - 1), its old vertices at the even rows and columns (same indices, moved onto the part
// too), face labels, feature and clipping edges carried over, base_direction kept. The snap's
// reach is the new mesh's mean edge length; its report goes to `snap` when given.
Segments subdivide_segments(const Segments& segments, const Mesh& part, SnapReport* snap = nullptr);

}  // namespace scallop
