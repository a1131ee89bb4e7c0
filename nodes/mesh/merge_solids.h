// Solids that overlap merged into one (mesh.repair's last step): a CAD assembly exported as one
// STL holds closed shells that cross each other (the ABC plate: three solids, two of them
// overlapping), so faces of one lie inside another. Nothing downstream can take such faces for
// the part's surface: the signed distance flips sign across them, segmentation and quads follow
// them. Their union, by CGAL's corefinement (Polygon_mesh_processing::corefine_and_compute_union),
// is the part.
#pragma once

#include <cstddef>

#include "nodes/types/mesh.h"

namespace scallop {

struct MergeSolidsReport {
  std::size_t solids_merged = 0;      // closed components merged into another (0: the mesh is as it was)
  std::size_t solids_not_merged = 0;  // crossing ones left apart: one intersects itself, or the union failed
};

// mesh  repaired and oriented (repair_mesh: closed components bound a volume, outward).
// Closed components whose surfaces intersect are replaced by their union, in triangles; every
// other face is kept as it is (polygons too), first and in its order, the unions' after them;
// vertices renumbered in order of first use. Open components are never merged; nor are solids
// one inside another without touching (their surfaces do not cross).
MergeSolidsReport merge_overlapping_solids(Mesh& mesh);

}  // namespace scallop
