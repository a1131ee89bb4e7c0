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
//   rectangle: corners sorted ascending c0..c3, L1..L4 the chord lengths of the four sides
//         c0..c1, c1..c2, c2..c3, c3..c0; the longer pair along u (W >= H, so that zig-zag
//         passes, iso-u lines, run the patch's short way): when L1 + L3 >= L2 + L4,
//         c0 -> (0,0), c1 -> (W,0), c2 -> (W,H), c3 -> (0,H) with W = (L1 + L3) / 2,
//         H = (L2 + L4) / 2; otherwise c0 -> (W,0), c1 -> (W,H), c2 -> (0,H), c3 -> (0,0) with
//         W = (L2 + L4) / 2, H = (L1 + L3) / 2 (the same orientation); each side mapped by
//         chord length along its edge.
// Chord lengths are measured along smoothed_loop(P, outer, half_window), not through the raw
// loop points.
// Throws std::invalid_argument for a short loop, a bad index, a zero-length loop or side, or bad
// corners.
// half_window  the smoothing of the loop before its chord length is measured (smoothed_loop);
//        0 measures through the loop points themselves (an exact polygon)
UVMap map_boundary(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer,
                   BoundaryDomain domain, std::vector<int> corners = {}, int half_window = kLoopSmoothing);

// Q[i] = mean of the positions of loop[i - w .. i + w] (indices around the closed loop),
// w = min(half_window, (#loop - 1) / 2). Throws std::invalid_argument for a loop of < 3 points
// or a bad index.
std::vector<Eigen::Vector3d> smoothed_loop(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                                           int half_window = kLoopSmoothing);

// The outer boundary band. Paper section 2.2 fixes the boundary points; our detected boundary is
// a band one or two points thick and the ordered loop zig-zags through it. Fixing the loop
// points on the domain's edge squashes that zig-zag flat, and the flagged band points off the
// loop, left free, can land outside the domain: both fold the map at the edge. So every band
// point is fixed at its projection on the smoothed loop, moved into the domain by its depth
// inside that loop times the map's derivative along that depth (band_values), which a first
// solve with all depths zero measures on free "probe" points just inside the band
// (band_depth_slope).
struct BandPoint {
  int index = 0;         // point index
  int segment = 0;       // segment of the smoothed outer loop it projects on: Q[segment] -> Q[segment+1]
  double t = 0;          // position on that segment, 0..1
  double depth = 0;      // distance inside the band's outer envelope (mm, >= 0), in the point's tangent plane
  double max_depth = 0;  // the smoothed loop's radius of curvature there (mm)
  bool fixed = false;    // true: a band point (Dirichlet); false: a probe (free)
  bool on_loop = false;  // on the outer loop itself
};

// Loop steps: flagged points within kBandWidth local loop steps of the smoothed loop form the
// band (farther ones are false boundary points inside the patch, at sampling voids); probes lie
// kBandWidth to 3 kBandWidth steps inside. kScaleWindow: half width (loop segments) over which
// the probes' depth slope is averaged (and the outer envelope taken); kMaxSlope: its clamp.
constexpr double kBandWidth = 3.0;
constexpr int kScaleWindow = 8;
constexpr double kMaxSlope = 2.0;
// Band points are offset at most this fraction of the way to a rectangle corner in (u,v).
constexpr double kCornerReach = 0.8;

// P            #P by 3 positions (mm);  N  #P unit normals, or empty (least-squares plane normal)
// is_boundary  #P flags (detect_boundary);  loops  all loops (order_boundary_loops)
// outer        the outer loop (loops[0])
// Band points: the outer loop's points and every flagged point on no loop within kBandWidth
// steps of the smoothed loop and nearer to it than to any hole loop point (hole bands stay free:
// natural boundaries). Probes: other points kBandWidth..3 kBandWidth steps inside, not nearer to
// a hole. Each is projected on the nearest segment of smoothed_loop(P, outer), except the loop
// points within kLoopSmoothing positions of a rectangle corner (corners: positions in outer, as
// UVMap::corners), which keep their place (segment = their position, t = 0); its depth is
// its distance inside that loop (in its tangent plane, along the loop's left normal) less the
// smallest such signed distance of the band points projecting within kScaleWindow segments.
// Returns band points and probes, ascending index. Throws std::invalid_argument for mismatched
// sizes or a bad loop.
std::vector<BandPoint> outer_band(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                                  const std::vector<std::uint8_t>& is_boundary,
                                  const std::vector<std::vector<int>>& loops, const std::vector<int>& outer,
                                  const std::vector<int>& corners = {});

// Dirichlet values of the band points (not the probes) for the boundary map `map` of the same
// outer loop: boundary_uv interpolated at the projection ("base"), plus depth times the map's
// derivative along the inward depth direction, slope[segment] = (a, b): a along the domain's
// inward normal (normal to the segment's (u,v) chord), b along the boundary's direction of
// travel (slope empty: (1, 0), an isometric offset). The depth is capped at max_depth and, for a
// rectangle, at kCornerReach of the depth whose offset would reach the nearest corner in (u,v),
// as (arc length, depth) stop being one-to-one there; band points off the loop deeper than the
// cap are left out (free), deeper loop points are held at the cap.
// Returns (point index, uv) pairs, ascending index.
std::vector<std::pair<int, Eigen::Vector2d>> band_values(const std::vector<BandPoint>& band, const UVMap& map,
                                                         const std::vector<Eigen::Vector2d>& slope = {});

// The derivative of a map along the inward depth direction near its outer loop, measured on the
// probes: for each loop segment, the mean over the probes projecting within kScaleWindow segments
// of (uv - base) / depth in (inward normal, tangent) components, clamped to [0, kMaxSlope] and
// [-kMaxSlope, kMaxSlope];
// zero where there is no probe. uv: #P positions of a map solved with every band point at its
// base (band_values with zero slopes). Near a corner of the outline that the domain does not
// have (a rectangle's corner on a disk, a spike) the map is far from isometric: the normal
// component drops well below 1 and the tangential one shears, and the band must follow that.
std::vector<Eigen::Vector2d> band_depth_slope(const std::vector<BandPoint>& band, const UVMap& map,
                                              const std::vector<Eigen::Vector2d>& uv);

// The 4 sharpest convex turning points of a closed loop, as positions in `loop`, ascending.
// Measured on smoothed_loop(P, loop, half_window): the turning angle at a point is the angle between the
// chords to the loop points an arc length h = L / 48 before and after it (interpolated), which
// averages boundary noise over several samples. Only left turns about the loop's least-squares
// plane normal (oriented so that the loop runs counter-clockwise around it) count: a notch is no
// corner of a rectangle. Corners are taken greedily by decreasing angle at least L / 16 of arc
// apart. When fewer than 4 points turn by 30 degrees or more (a smooth outline has no corners),
// the corners are the sharpest point and the 3 points a quarter, half and three quarters of L
// after it.
std::vector<int> detect_corners(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                                int half_window = kLoopSmoothing);

// Parses "i,j,k,l" (positions in a loop of `loop_size` points); empty text gives an empty vector.
// Throws std::invalid_argument naming the problem (not 4 numbers, out of range, repeated).
std::vector<int> parse_corners(const std::string& text, std::size_t loop_size);

}  // namespace scallop
