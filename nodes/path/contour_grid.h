// Contour-parallel finishing passes on a rectangle-parameterised surface, from the scallop limit
// (papers/point-clouds-to-workpieces.md, Algorithm 1 and the path intervals after Lin and Koren),
// with the scallop between every two neighbouring contours evaluated on the surface, not trusted
// to the step formula.
//
// The contours are nested rectangles of the (u, v) domain [0, W] x [0, H] (a B-spline patch: the
// unit square): contour 0 is the border, contour k + 1 lies inside contour k, each of its four
// sides moved in from contour k's by its own step. The paper's grid lines (7) and (8) are the
// sides' u and v: t_0 = dt_0, t_1 = dt_0 + dt_1, ... from each end.
//
// A side's step (Algorithm 1, steps 1, 2 and 8): on `side_samples` points of the side, the side
// interval l_s = sqrt(8 h r / (1 + r kappa)) (kappa the normal curvature across the pass, convex
// positive; step_size.h), turned into a parameter step across the pass (formula (4): l_s /
// (|r_u| sin theta), exact for any angle theta between r_u and r_v); the smallest is taken.
// Algorithm 1's step 3 checks the scallop at the corner between the grid lines; here the scallop
// is evaluated everywhere between contour k and k + 1: at 9 fractions across each side's strip
// (corners included, as they belong to two strips) and along it every eighth of the strip's width
// (at least twice side_samples points), the worst places then refined by a pattern search; the
// scallop at a surface point p with normal n being the smallest t >= 0 at which p + t n comes
// within r of a ball-centre polyline of either contour (../shared/tools/verify.py's
// definition). Where a strip's scallop exceeds h its side's step is shrunk (by 0.995 sqrt(h /
// scallop): the scallop grows with the square of the step) and the check repeated. The corners,
// where three balls' fields meet, hold every contour's steps under the formula's (about 0.85 of
// it on a plane), so each side starts from its formula's step times the share the same side of
// the contour before kept, grown by 0.995 sqrt(h / its scallop) (at most 1): on the fandisk's 76
// patches that took the contours 1 659 tries where they had taken 3 049. Where the two sides of a pair would cross, both stop at
// their middle: the last contour is a segment (or a point), traversed there and back.
//
// Along a contour, the forward step is formula (2), l_f = sqrt(8 e R - 4 e^2) with R the radius
// of curvature of the contact curve (step_size.h), at most max_segment, and then checked: the
// ball-centre chord may stray at most e from the ball-centre curve at 1/4, 1/2 and 3/4 of each
// segment, and at most part_clearance_tolerance(e) = max(e/4, 0.001) toward the surface (where
// post.setup_programs would lift the ball and leave stock the scallop checks do not see: 0.0527
// for h = 0.05 on the bundled domed block's top); the step is halved where it does.
//
// The surface is taken as exact here (SurfaceSample::uncertainty is not used: the B-spline patch
// certificate of the whole part is post.simulate's job), and the balls are not kept off other
// faces (the gouge guard's job).
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/geom/parametric_surface.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct ContourGridOptions {
  double tool_radius = 3;        // r (mm), > 0
  double scallop_height = 0.01;  // h (mm), 0 < h < r
  double chord_error = 0.005;    // e (mm), > 0
  double max_segment = 5;        // longest forward step (mm), > 0
  int side_samples = 33;         // k: points per side where the step is computed (>= 2)
  std::size_t max_contours = 5000;  // more than this: refused (a vanishing step), with where
  std::function<void(double, const std::string&)> progress;  // optional
  // Optional: the scallop limit on the (u, v) box [u0, u1] x [v0, v1], at most scallop_height (the
  // surface lies off the part there, and the part's scallop may be that much more). Asked for the
  // ring a contour's sides may step across; unset: scallop_height everywhere.
  std::function<double(double u0, double u1, double v0, double v1)> scallop_limit;
};

struct ContourGridResult {
  std::vector<ToolpathPass> passes;  // one per contour, outermost first, each closed (last point = first)
  nlohmann::json report;             // contours, points, grid lines, steps across u and v (parameter
                                     // units), scallop and chord found by the checks; where the patch
                                     // curves concave tighter than the ball across the contours,
                                     // unreachable_samples and concave_radius_min (mm: a ball of a
                                     // smaller radius would follow it)
};

// surface  a rectangle domain (UVDomain::Kind::Rectangle, width and height > 0).
// Throws std::invalid_argument with a clear message for bad options, a disk domain, or more
// contours than max_contours.
ContourGridResult plan_contour_grid(const ParametricSurface& surface, const ContourGridOptions& options);

}  // namespace scallop
