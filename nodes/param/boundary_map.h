// Boundary map by chord length (paper section 2.2): the ordered outer loop goes to a circle
// (contour-parallel paths) or to a rectangle (direction-parallel paths).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "nodes/types/param.h"

namespace scallop {

enum class BoundaryDomain { Disk, Rectangle };

// Half width (loop points) of the moving average that smooths the outer loop before its chord
// length is measured. The detected boundary is a band one or two points thick and the ordered
// loop zig-zags through it, which makes its raw chord length 15-20 % longer than the true
// outline; averaging over 2 * 3 + 1 points removes the zig-zag (its cross-band offsets cancel)
// while rounding a corner over only ~3 sampling steps.
constexpr int kLoopSmoothing = 3;

// Flagged points farther than this many local loop steps from the smoothed outer loop are false
// boundary points inside the patch (sampling voids), not part of the outer band.
constexpr double kBandWidth = 3.0;

// "disk", "rectangle"; throws std::invalid_argument otherwise.
BoundaryDomain parse_boundary_domain(const std::string& name);

// P      #P by 3 positions (mm)
// outer  the outer loop, >= 3 point indices in order (counter-clockwise seen from the normals'
//        side, as order_boundary_loops gives it: the uv domain then has the same orientation)
// corners  rectangle only: 4 distinct positions in `outer` (any order), or empty for
//        detect_corners
// Returns a UVMap with uv empty and: domain, outer_loop = outer, boundary_uv (one per loop
// point), and
//   disk: radius R = L / (2 pi), L the length of the smoothed loop (smoothed_loop); point i at angle 2 pi lambda_i, lambda_i the
//         chord length from outer[0] over L, centred at the origin;
//   rectangle: corners sorted ascending, c0 -> (0,0), c1 -> (W,0), c2 -> (W,H), c3 -> (0,H) with
//         W = (L1 + L3) / 2, H = (L2 + L4) / 2, L1..L4 the chord lengths of the four sides
//         c0..c1, c1..c2, c2..c3, c3..c0; each side mapped by chord length along its edge.
// Chord lengths are measured along smoothed_loop(P, outer), not through the raw loop points.
// Throws std::invalid_argument for a short loop, a bad index, a zero-length loop or side, or bad
// corners.
UVMap map_boundary(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer,
                   BoundaryDomain domain, std::vector<int> corners = {});

// Q[i] = mean of the positions of loop[i - w .. i + w] (indices around the closed loop),
// w = min(half_window, (#loop - 1) / 2). Throws std::invalid_argument for a loop of < 3 points
// or a bad index.
std::vector<Eigen::Vector3d> smoothed_loop(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                                           int half_window = kLoopSmoothing);

// Dirichlet values for the whole outer boundary band (paper section 2.2 fixes the boundary; our
// detected boundary is a band one or two points thick, and the loop zig-zags through it).
// N            #P unit normals, or empty (the cloud's least-squares plane normal is used)
// is_boundary  #P flags (detect_boundary);  loops  all loops (order_boundary_loops)
// map          the boundary map of loops[0] (map_boundary)
// The band: the outer loop's points, and every flagged point on no loop within kBandWidth local
// loop steps of the smoothed outer loop and nearer to it than to any hole loop point (hole bands
// stay free: natural boundaries). Each band point is projected on the smoothed outer loop
// (smoothed_loop); its value interpolates boundary_uv of that segment's two loop points, moved
// into the domain (normal to the segment's (u,v) chord) by the point's distance d >= 0 inside the
// smoothed loop, measured in its tangent plane (points outside it get d = 0). The map of the band
// then follows its geometry: a loop point that zig-zags inwards lands inside the domain, not on
// its edge, and band points off the loop are no free unknowns that could land outside the domain.
// Returns (point index, uv) pairs, ascending index, outer-loop points included.
// Throws std::invalid_argument for mismatched sizes.
std::vector<std::pair<int, Eigen::Vector2d>> outer_band_values(const std::vector<Eigen::Vector3d>& P,
                                                               const std::vector<Eigen::Vector3d>& N,
                                                               const std::vector<std::uint8_t>& is_boundary,
                                                               const std::vector<std::vector<int>>& loops,
                                                               const UVMap& map);

// The 4 sharpest turning points of a closed loop, as positions in `loop`, ascending.
// Measured on smoothed_loop(P, loop): the turning angle at a point is the angle between the
// chords to the loop points an arc length h = L / 48 before and after it (interpolated), which averages boundary noise over several
// samples; corners are taken greedily by decreasing angle at least L / 16 of arc apart. When
// fewer than 4 points turn by 30 degrees or more (a smooth outline has no corners), the corners
// are the sharpest point and the 3 points a quarter, half and three quarters of L after it.
std::vector<int> detect_corners(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop);

// Parses "i,j,k,l" (positions in a loop of `loop_size` points); empty text gives an empty vector.
// Throws std::invalid_argument naming the problem (not 4 numbers, out of range, repeated).
std::vector<int> parse_corners(const std::string& text, std::size_t loop_size);

}  // namespace scallop
