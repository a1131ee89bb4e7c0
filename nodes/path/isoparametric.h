// Iso-parametric finishing passes planned straight from a parameterised point cloud (paper:
// "Iso-parametric tool-path planning for point clouds", section 4), with the scallop limit
// checked between every two passes rather than trusted to the step formula.
//
// Pass coordinates (s, t): s is the side coordinate (constant along a pass), t the forward one.
//   zigzag  (rectangle map [0,W] x [0,H]): s = u in [0, W], t = v in [0, H]. Passes are the
//           iso-u lines u = 0 ... W (the first and last on the boundary), cut forward along v
//           and in alternate directions (the paper's convention: forward = v, side = u).
//   contour (disk map of radius R): s = R - rho, t = theta in [0, 2 pi]. Passes are the circles
//           rho = R (the boundary) inwards, each closed and cut counter-clockwise in uv; the last
//           "pass" is the single point at the centre.
// With `outline` (both patterns), a closed pass runs through the outer loop's own points
// (the map's outer_loop, with the cloud's positions, normals and uncertainties): the interpolant
// rounds the outline's corners off, and zig-zag passes end on the edges v = 0, H, so without it
// the rim between pass ends and at corners is left to the balls' ends. The contour pattern cuts
// it first, the zig-zag last.
//
// Along a pass, the forward step starts from formula (2) (chord deviation e, the pass's own
// curvature) and is then checked on the ball-centre polyline, at 1/4, 1/2, 3/4 of each segment
// and at least every half sampling step of the map: the chord may lie at most the overcut budget
// below the centre curve (0.9 e on an exact cloud, see "Margins" below), at most min(e, h/10)
// above it (undercut, which adds to the scallop), and at most 0.9 e away in any direction.
//
// Between passes, the side step is the smallest over the points of the current pass of formula
// (3) (where r_s and r_t are within `conformal_tolerance` of orthogonal) or formula (4)
// (elsewhere), chosen per point. The next pass is then built and the scallop between the two
// ball-centre polylines is evaluated exactly (the first hit of the surface normal ray with the
// swept balls, as ../shared/tools/verify.py defines it) along the strip; where it exceeds its
// limit the step is shrunk (secant on sqrt(h), then bisection) and the pass rebuilt.
//
// Margins. Where the cloud is known only to +-delta (its per-point uncertainty from
// cloud.denoise, or the surface_error option, whichever is larger), the scallop on the estimate
// may reach only safety_factor * h - 1.25 delta, the chord overcut max(e/4, 0.9 e - delta), and
// the ball is kept stock = overcut + 1.5 delta - 0.9 e (when positive) above the estimate, so
// that the limits hold on the real surface (isoparametric.cpp, Margins).
//
// Every ball centre is then kept off the cloud: where a cloud point lies more than
// min(e/4, 0.9 e - 1.5 delta) inside the ball (a concave place of radius below r, a kink), the
// ball and its contact are lifted along the normal; segments next to lifted vertices (or whose
// chord check failed) are sampled every r/16 and their ends lifted until no cloud point is more
// than min(e/2, 0.9 e - 1.5 delta) inside the swept ball. The report's "ball_lifted" gives how
// many points were lifted and by how much at most (mm).
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "nodes/types/cloud.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct IsoparametricOptions {
  std::string pattern = "zigzag";    // "zigzag" (rectangle map) or "contour" (disk map)
  double tool_radius = 3;            // r, ball radius (mm), > 0
  double scallop_height = 0.01;      // h (mm), 0 < h < r
  double chord_error = 0.005;        // e (mm), > 0
  double safety_factor = 1.0;        // plan for h * safety_factor, in (0, 1]
  double surface_error = 0;          // delta (mm), >= 0: the cloud's surface is known to at least
                                     // +-delta everywhere (see Margins above)
  double conformal_tolerance = 5.0;  // degrees: |angle(r_s, r_t) - 90| above this uses formula (4)
  double max_segment = 5.0;          // longest forward step (mm), > 0
  int interpolation_k = 20;          // neighbours per local fit (see uv_interpolation.h)
  bool outline = true;               // a last closed pass through the outline's own points
  // With `outline`, closed passes offset outward from the outer loop cut this band beyond it
  // (mm along the surface; the real outline lies beyond the cloud's outermost points), and
  // passes offset into each hole from its loop the same band (no deeper than half the hole's
  // radius); -1: rim_band_width (step_size.h), three of the cloud's spacings; 0: none.
  double rim_band = -1;
  // Bounds on the work (a degenerate map or a noisy cloud makes the steps vanish): more passes
  // or points than these, or more than min(200000, max_points) points in one pass, stop the
  // planner with std::invalid_argument saying where and why. More passes than max_passes
  // estimated before planning (the report's "estimate": the side interval on a plane across the
  // patch) refuse at once, with the estimate.
  std::size_t max_passes = 5000;
  std::size_t max_points = 5000000;
  std::function<void(double, const std::string&)> progress;  // optional
};

struct IsoparametricResult {
  Toolpath toolpath;
  nlohmann::json report;
};

// cloud      #P points (mm) with #P upward unit normals, and optionally #P uncertainties (mm)
// neighbors  the cloud's k nearest neighbours (#P rows; used for the sampling scale)
// map        uv of every point; domain "rectangle" or "planar" (zigzag), "disk" (contour)
// Returns the passes (contact points, normals, uv; ordered for cutting) and a report: passes,
// points, side steps and intervals (min/max), forward intervals, where formula (4) was used,
// the largest scallop and chord deviations found by the checks, concave regions whose normal
// curvature radius is below r (count, location, size), the margins kept for the cloud's
// uncertainty (surface_error: median, max, stock, too-uncertain points), the rim passes
// (outline_passes) and the band passes beyond the outer loop and into the holes (rim_band:
// width, passes; cut after the rim passes, innermost first), and warnings.
// Throws std::invalid_argument with a clear message for bad input (empty cloud, no normals,
// size mismatch, wrong domain for the pattern, bad options, a cloud too uncertain for h).
// loops      optional: the patch's boundary loops (outer first, then holes; indices into cloud).
//            A hole's uv polygon is not cut: passes crossing it are split into pieces on the
//            patch (the tool lifts over the hole), and with `outline` a rim pass runs around it.
// field_uncertainty  optional, #P: the cloud's height field's uncertainty at each point
//            (cloud.surface_band's), what the margins are planned with where the cloud has
//            per-point uncertainties; computed here when not given.
IsoparametricResult plan_isoparametric(const PointCloud& cloud, const Neighborhoods& neighbors,
                                       const UVMap& map, const IsoparametricOptions& options,
                                       const BoundaryLoops* loops = nullptr,
                                       const std::vector<double>* field_uncertainty = nullptr);

}  // namespace scallop
