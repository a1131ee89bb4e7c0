// Boundary map by chord length (paper section 2.2): the ordered outer loop goes to a circle
// (contour-parallel paths) or to a rectangle (direction-parallel paths).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/types/param.h"

namespace scallop {

enum class BoundaryDomain { Disk, Rectangle };

// "disk", "rectangle"; throws std::invalid_argument otherwise.
BoundaryDomain parse_boundary_domain(const std::string& name);

// P      #P by 3 positions (mm)
// outer  the outer loop, >= 3 point indices in order (counter-clockwise seen from the normals'
//        side, as order_boundary_loops gives it: the uv domain then has the same orientation)
// corners  rectangle only: 4 distinct positions in `outer` (any order), or empty for
//        detect_corners
// Returns a UVMap with uv empty and: domain, outer_loop = outer, boundary_uv (one per loop
// point), and
//   disk: radius R = L / (2 pi), L the loop length; point i at angle 2 pi lambda_i, lambda_i the
//         chord length from outer[0] over L, centred at the origin;
//   rectangle: corners sorted ascending, c0 -> (0,0), c1 -> (W,0), c2 -> (W,H), c3 -> (0,H) with
//         W = (L1 + L3) / 2, H = (L2 + L4) / 2, L1..L4 the chord lengths of the four sides
//         c0..c1, c1..c2, c2..c3, c3..c0; each side mapped by chord length along its edge.
// Throws std::invalid_argument for a short loop, a bad index, a zero-length loop or side, or bad
// corners.
UVMap map_boundary(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer,
                   BoundaryDomain domain, std::vector<int> corners = {});

// The 4 sharpest turning points of a closed loop, as positions in `loop`, ascending.
// The turning angle at a point is the angle between the chords to the loop points an arc length
// h = L / 48 before and after it (interpolated), which averages boundary noise over several
// samples; corners are taken greedily by decreasing angle at least L / 16 of arc apart. When
// fewer than 4 points turn by 30 degrees or more (a smooth outline has no corners), the corners
// are the sharpest point and the 3 points a quarter, half and three quarters of L after it.
std::vector<int> detect_corners(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop);

// Parses "i,j,k,l" (positions in a loop of `loop_size` points); empty text gives an empty vector.
// Throws std::invalid_argument naming the problem (not 4 numbers, out of range, repeated).
std::vector<int> parse_corners(const std::string& text, std::size_t loop_size);

}  // namespace scallop
