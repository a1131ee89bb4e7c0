// The planar map: a height field's points parameterised by their own xy, turned so that the
// passes of a zig-zag (iso-u lines) run in a chosen direction. It cannot fold over (a height
// field's points are apart in xy), whatever the outline: a raster whose side steps the planner
// still chooses from the scallop limit, where a harmonic map of a ragged or notched outline
// folds or is stretched out of use (a real scan's steep flanks trimmed away).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/types/param.h"

namespace scallop {

// P       #P by 3 positions (mm), at least 3, finite
// outer   the outer loop, >= 3 point indices in order (its uv is boundary_uv)
// angle   the passes' direction in xy, degrees from +x; < 0: automatic, across the points' longer
//         principal extent in xy (the patch's short way, as the harmonic zig-zag's passes run)
// Returns a UVMap with domain "planar": uv[i] = R (xy_i - o), R the rotation taking the passes'
// direction to +v, o such that the points span [0, width] x [0, height]; outer_loop = outer,
// boundary_uv its points' uv, no corners, residual 0. The patch is the outer loop's inside (and
// outside the holes): the rest of the rectangle is off the patch.
// Throws std::invalid_argument for fewer than 3 points, a non-finite point, a loop of fewer than 3
// points or a bad index, or points that span no area in xy.
UVMap planar_map(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer, double angle = -1);

}  // namespace scallop
