// Forward and side steps of iso-parametric tool paths, and the local differential geometry they
// need (paper: "Iso-parametric tool-path planning for point clouds", sections 3.1-3.2 and
// appendix A).
//
// Sign convention (the same as ../shared/tools and the rest of scallop): normals point up, away
// from the material, and a normal curvature is positive where the surface is convex seen from
// the tool (a dome of radius rho has kappa = +1/rho, a bowl -1/rho). With r_uu the second
// derivative along a direction, kappa = -(n . r_uu) / |r_u|^2.
#pragma once

#include <algorithm>

#include <Eigen/Core>
#include <cmath>

namespace scallop {

// Coefficients of the first (E, F, G) and second (L, M, N) fundamental forms at a point of a
// parametric surface r(u, v) with unit normal n: E = r_u.r_u, F = r_u.r_v, G = r_v.r_v,
// L = n.r_uu, M = n.r_uv, N = n.r_vv (lengths in mm, parameters in the map's units).
struct FundamentalForms {
  double E = 1, F = 0, G = 1, L = 0, M = 0, N = 0;
};

FundamentalForms fundamental_forms(const Eigen::Vector3d& ru, const Eigen::Vector3d& rv,
                                   const Eigen::Vector3d& ruu, const Eigen::Vector3d& ruv,
                                   const Eigen::Vector3d& rvv, const Eigen::Vector3d& n);

// Normal curvature (1/mm, convex positive) along the parameter direction (du, dv):
// kappa = -II/I (paper section 3.1, with our sign). (du, dv) must not be (0, 0).
double normal_curvature(const FundamentalForms& f, double du, double dv);

// Principal curvatures (1/mm, convex positive) as {smallest, largest}: the eigenvalues of the
// shape operator -I^-1 II.
Eigen::Vector2d principal_curvatures(const FundamentalForms& f);

// Forward interval (mm) along a pass, paper formula (2): l_f = sqrt(8 e R - 4 e^2), where R is
// the radius of curvature of the pass itself (the paper's R cos(theta), Meusnier) and e the
// allowed chord deviation (mm). curvature = 1/R >= 0 (1/mm); returns +infinity for a straight
// pass (curvature 0), and 2R when e >= 2R (the chord may span the whole circle's diameter).
double forward_interval(double chord_error, double curvature);

// How near the part a ball centre may come, less than r (mm): post.setup_programs lifts a ball
// (and inserts lifted points into a move) nearer than r - this, so a planner whose ball-centre
// chords dip toward the surface keeps the dip within it (a lifted point leaves stock that the
// scallop checks did not see). A quarter of the chord error, at least 1 micron.
inline double part_clearance_tolerance(double chord_error) { return std::max(0.25 * chord_error, 1e-3); }

// How much of the chord error e (mm) a path may use where the surface estimate may lie up to
// delta (mm) off the real surface: 0.9 e less 0.15 delta. The rest is left for the difference
// between two fits of the same cloud: the planner and the gouge guard check the ball at the
// places they sample (positions, their foot points, the cloud's points), the certificate
// (post.simulate) at its own grid between them, where the height field's uncertainty is its fit
// over another set of neighbours. That uncertainty is rough: on the noisy dome (50 000 points,
// sigma 0.02, denoised) it differs from itself 0.1 mm away by 7.5 % at the 99.9th percentile,
// 22 % at most; a zig-zag program the guard held to 0.9 e there had a certificate gouge bound
// 0.0107 > e = 0.01, 0.077 delta above what the guard had seen beside it. 0.1 e alone covered
// a clean cloud, where delta is nearly 0.
constexpr double kUncertaintyRoughness = 0.15;
inline double gouge_budget(double chord_error, double delta) {
  return 0.9 * chord_error - kUncertaintyRoughness * delta;
}

// How far beyond a cloud's outer loop (mm, along the surface) the real outline may lie: the loop
// runs through the outermost points, and a random sample leaves gaps at its edge. On the
// catalog's 50 000-point clouds the true outline lies up to 2.7 mean spacings beyond the loop
// (the freeform's spike: 1.35 mm at a spacing of 0.50; bench/outline_gap.py); three spacings.
// cloud_spacing  the cloud's mean spacing in xy (HeightFieldModel::spacing).
inline double rim_band_width(double cloud_spacing) { return 3 * cloud_spacing; }
// How far beyond the outer loop post.simulate certifies by default: the cloud's support, a
// spacing past its outermost points (they sit about half a spacing inside the edge). The band
// passes cut three; beyond one the field is extrapolated, its uncertainty grown (on the canopy's
// 68 degree rim to 0.026 mm 1.7 mm out), and the part is seldom there (the true outline lies a
// median 0.2 mm beyond the loop).
inline double certified_rim_band(double cloud_spacing) { return cloud_spacing; }

// How the gouge budget is shared where the surface estimate may lie up to delta off the real
// surface, either way (cloud.denoise's uncertainty: an honest bound, noise and shape bias). The
// real surface may be delta higher than the estimate, so a ball touching the estimate may cut
// delta into it: the chord overcut shrinks first (down to e/4, which only costs forward points),
// and what is still over the budget B becomes stock, a lift of the ball above the estimate.
// Where delta <= B - e/4: overcut B - delta, stock 0; above: overcut e/4, stock delta + e/4 - B.
// Either way overcut + delta - stock = B.
struct ChordBudget {
  double overcut;  // mm the ball-centre chord may dip below the offset surface between positions
  double stock;    // mm the ball is kept above the estimate
  double reach;    // mm a planned position may reach into the estimate raised by delta: delta - stock
};
inline ChordBudget chord_budget(double chord_error, double delta) {
  const double budget = gouge_budget(chord_error, delta);
  ChordBudget b;
  b.overcut = std::max(0.25 * chord_error, budget - delta);
  b.stock = std::max(0.0, b.overcut + delta - budget);
  b.reach = delta - b.stock;
  return b;
}

// True where a ball of radius r cannot reach the bottom of a concave section: normal
// curvature radius below r (1 + r kappa <= 0).
bool ball_cannot_reach(double tool_radius, double kappa);

// Side interval (mm) between passes for scallop height h (mm) with a ball of radius r (mm)
// across a direction of signed normal curvature kappa (1/mm, convex positive), paper section
// 3.2: l_s = sqrt(8 h r R / (R + r)) convex, sqrt(8 h r R / (R - r)) concave, i.e.
// l_s = sqrt(8 h r / (1 + r kappa)); exactly sqrt(8 r h) on a plane. Returns +infinity where
// ball_cannot_reach(r, kappa): no step keeps the scallop there, the caller must report it.
double side_interval(double scallop_height, double tool_radius, double kappa);

// Parameter side step from a surface interval l_s (mm).
// Formula (3), for a conformal point: du = l_s / |r_u|.
double side_step_conformal(double side_interval, double ru_norm);
// Formula (4), appendix A, where r_u and r_v meet at an angle theta != pi/2: the interval is
// measured perpendicular to the pass (direction r_v), so du = l_s / (|r_u| cos|theta - pi/2|)
// = l_s / (|r_u| sin(theta)). theta in (0, pi) (radians).
double side_step_corrected(double side_interval, double ru_norm, double theta);

// Height (mm) of the cusp left between two balls of radius r whose centres are w apart (mm) on a
// plane: r - sqrt(r^2 - w^2 / 4). The exact value that sqrt(8 r h) approximates to first order.
double cusp_height_plane(double tool_radius, double spacing);

// First entry t along the ray o + t d (d unit) into the capsule of radius r around segment
// [a, b] (a == b: a ball). Returns 0 when o is inside, +infinity when the ray misses it or the
// capsule lies wholly behind o (t < 0). Given `before`, +infinity also where the segment stands
// farther than r + before from o (the entry cannot come before `before`): a caller keeping the
// least entry over many segments passes the least so far and skips the far ones' work.
double ray_capsule_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                         const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                         double before = INFINITY);

}  // namespace scallop
