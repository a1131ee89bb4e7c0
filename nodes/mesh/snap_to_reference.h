// Moves a remeshed surface's vertices back onto the surface it was made from (mesh.quad_remesh).
//
// QuadriFlow places its vertices by its own smoothing, and near sharp features and the corners
// where they meet they lie off the part: on the bundled domed block (1.2 mm quads) up to 0.105 mm
// outside a vertical edge and 0.055 mm at a corner. The B-spline patches fitted to them carry
// that error into the tool paths, which follow a surface the part does not have (1.1 h of scallop
// measured there). Here each vertex of `remeshed` moves, by at most `reach`:
//   - a corner (three or more of remeshed's feature edges, border edges counted) to the nearest
//     corner of the reference's features within reach (three or more reference feature or border
//     edges);
//   - a vertex on a feature edge (or a corner with no reference corner in reach) to the nearest
//     point of the reference's feature or border edges within reach that runs within 30 degrees of
//     one of its own feature edges (so a parallel feature nearby is not taken);
//   - every other vertex, and one with no such feature point, to the nearest point of the
//     reference's faces (when that is within reach).
// Where a face's normal would turn by more than 45 degrees (two corners snapped onto one, a vertex
// pulled across a feature), its vertices go back where they were, until no face turns.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

struct SnapReport {
  std::size_t corners = 0;           // vertices moved onto a reference corner
  std::size_t feature_vertices = 0;  // onto a reference feature or border edge
  std::size_t surface_vertices = 0;  // onto the reference's faces
  std::size_t kept = 0;              // left where they were (nothing in reach, or a face would turn)
  double off_surface_max = 0;        // mm: the largest distance from a vertex to the reference's faces, before
  double moved_max = 0;              // mm: the largest move
};

// remeshed            any polygon mesh; its feature_edges (vertex pairs) and border edges are its features
// reference           the surface remeshed was made from (any polygons), with at least one face
// reference_features  the reference's feature edges as vertex pairs (its border edges are added)
// reach               mm, > 0: the farthest a vertex moves
// Returns the report; remeshed's vertices are moved in place, its faces and feature_edges kept.
// Throws std::invalid_argument for a reference without faces or reach <= 0.
SnapReport snap_to_reference(Mesh& remeshed, const Mesh& reference,
                             const std::vector<std::array<std::uint32_t, 2>>& reference_features, double reach);

}  // namespace scallop
