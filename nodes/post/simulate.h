// Cutting simulation: what a ball-end path leaves on the surface a point cloud samples.
//
// The product's own certificate, with the definitions of ../shared/tools/verify.py (README
// there): the surface is a height field z(x, y) fitted to the cloud; it is sampled on a square xy
// grid rotated by 0.3 rad (nodes/post/surface_grid.h: the samples need no path, so a graph may
// take them beforehand); for every sample p with upward unit normal n, with C the polyline of
// ball centres of the feed moves and d the exact distance to C,
//   gouge   = max(0, r − d(p)),
//   scallop = smallest t ≥ 0 with d(p + t·n) ≤ r   (exact: first entry of the ray into the
//             union of capsules of radius r around the pieces of C, found analytically),
//   uncut   when no such t ≤ 20·h.
// Where the cloud carries an uncertainty delta (PointCloud::uncertainty: the real surface may lie
// up to delta off it), both are bounds for the real surface: gouge = max(0, r − d(p) + delta),
// scallop = its value at p + delta.
// pass: the whole patch (rim included, up to the outline) has scallop <= 1.01 h, gouge within
// the chord tolerance and nothing uncut; the interior figures are reported beside it.
// Fractions, percentiles and means are area-weighted. The 1000 highest values, and the highest of
// every cell of 32 spacings near the top (nodes/post/refinement_seeds.h), are refined with local
// grids down to 1/16 of the spacing so the maxima do not depend on the grid.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/geom/height_field_model.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/post/centre_index.h"
#include "nodes/types/simulation.h"
#include "nodes/types/surface_samples.h"
#include "nodes/types/toolpath.h"

namespace scallop {

// Ball centres of a planned path: consecutive contact points of each pass, c + r·n.
std::vector<CentreSegment> feed_centres(const Toolpath& path);
// Ball centres (tip + r·ẑ) of the feed and plunge moves of a linked path; rapid_length gets the
// total length of its rapid moves, and `rapids`, when given, their ball centres.
std::vector<CentreSegment> feed_centres(const LinkedPath& path, double& rapid_length,
                                        std::vector<CentreSegment>* rapids = nullptr);

// How near the rapids' balls of radius r come to the cloud's points, each raised by its
// uncertainty (the real surface may stand that high): the least distance less r along every
// rapid, marched by that distance itself (it cannot fall faster than the centre moves), to
// within tol / 2; a rapid whose least is below -tol goes through the surface. verify.py's check,
// against the points (between them a surface bulges by about spacing² / (8 × its radius)).
struct RapidClearance {
  double least = INFINITY;  // mm; +infinity without rapids
  Eigen::Vector3d at = Eigen::Vector3d::Zero();  // the ball centre there
  std::size_t through = 0;  // rapids below -tol
};
// points  #P by 3; uncertainty  null or #P (mm). Throws std::invalid_argument for r <= 0,
// tol <= 0, no points, or a non-finite centre.
RapidClearance rapid_clearance(const std::vector<Eigen::Vector3d>& points, const std::vector<double>* uncertainty,
                               const std::vector<CentreSegment>& rapids, double r, double tol);
// The same with a k-d tree over `points` at hand (HeightFieldModel::tree3d): none is built. The
// nearest raised point is searched among the points no farther than the nearest found so far
// plus the largest uncertainty (a point is raised by at most that): the same answer.
RapidClearance rapid_clearance(const std::vector<Eigen::Vector3d>& points, const std::vector<double>* uncertainty,
                               const KdTree<Eigen::Vector3d, 3>& tree, const std::vector<CentreSegment>& rapids,
                               double r, double tol);

struct SimulateOptions {
  double tool_radius = 0;   // r (mm)
  double scallop = 0;       // h, the scallop limit (mm)
  double chord = 0;         // e, the chord tolerance (mm): gouges up to max(e, 0.001) pass
  double spacing = 0;       // grid spacing (mm); 0: sqrt(8 r h) / 12
  double margin = 0;        // interior margin from the outline (mm); 0: sqrt(8 r h)
  std::size_t max_samples = 1500000;  // the spacing is raised to stay below this
  int fit_neighbors = 20;
  // The patch's outline as closed xy polygons (mm): loops[0] the outer one, the others holes.
  // Given, a sample is on the patch iff it is inside the outer polygon and outside every hole,
  // and the interior margin is measured from the polygons' edges. Empty: the outline is guessed
  // from the cloud (HeightFieldModel::inside), which on sparse clouds reaches past the real rim.
  std::vector<std::vector<Eigen::Vector2d>> loops;
  // With loops: the band off the patch, beyond the outer loop and into the holes, also counted
  // as the patch, its width along the surface (mm; a sample off the patch is on it within
  // rim_band × n_z of the nearest loop in xy, and never interior): part of what
  // path.isoparametric's band passes cut (the real outline, and a hole's real edge, lie beyond a
  // cloud's outermost points). < 0: certified_rim_band of the cloud's
  // spacing (nodes/path/step_size.h), one spacing; 0: none (the default: measured on the clean
  // canopy's 68 degree rim, one spacing out the extrapolation's uncertainty changes faster than
  // the guard samples it, and the contour program's gouge bound came out 0.0137 > e there while
  // verify.py passed it).
  double rim_band = 0;
  // Optional: the obstacle points of what is not machined (obstacle_points of cloud.trim_steep's
  // left_out: a steep wall beside the patch). A sample where the ball touching the surface (its
  // centre r along the normal) would come within obstacle_keep_off of one of them cannot be
  // reached by
  // this ball without cutting into them (path.gouge_guard keeps it off): not counted in the
  // scallop and uncut figures, but reported (beside_left_out: its area, fraction and where).
  // Gouges there count as everywhere. Must outlive the call.
  const std::vector<Eigen::Vector3d>* left_out = nullptr;
};

// Simulates the feed polyline `feed` (ball centres) over the surface `surface`: the samples
// (nodes/types/simulation.h), the grid spacing, the outline, the limits judged against
// (scallop_limit = h, gouge_tolerance = max(e, 0.001)) and the report.
// Report keys: scallop_max, scallop_max_interior, scallop_p99, scallop_p99_interior,
// scallop_mean, scallop_mean_interior, gouge_max, uncut_fraction, uncut_fraction_interior,
// cut_length, rapid_length, samples, samples_interior, samples_refined, samples_beyond_outline,
// beside_left_out (with left_out: {area_mm2, fraction, min, max} of the samples no ball reaches)
// (grid samples in the rim band), rim_band, spacing, margin,
// surface_area, surface_uncertainty_max (the cloud points' largest uncertainty),
// surface_uncertainty_max_sampled (the largest the bounds used at a grid sample: the
// HeightFieldModel's, its fit's misfit counted), tool_radius, scallop_limit, chord_limit, pass,
// fail_reasons (a bound over its limit says where, and how much of it is the surface's
// uncertainty there), worst (up to 10 places {x, y, z, kind: "gouge" | "uncut" | "scallop", value,
// interior, uncertainty: the surface's there, included in value}, worst first).
// Throws std::invalid_argument for r ≤ 0, h ≤ 0, an empty path, a non-finite centre, or loops
// whose outer polygon has fewer than 3 points or that have a non-finite point.
Simulation simulate_cut(const HeightFieldModel& surface, const std::vector<CentreSegment>& feed,
                        double rapid_length, const SimulateOptions& options,
                        const std::function<void(double)>& progress = {});
// The same at samples taken before (sample_surface_grid, post.surface_samples) with
// surface_grid_options(options) from a cloud of surface's size: the same simulation. Throws
// std::invalid_argument as above, and where the samples were taken for other options or another
// cloud's size (saying which).
Simulation simulate_cut(const HeightFieldModel& surface, const SurfaceSamples& samples,
                        const std::vector<CentreSegment>& feed, double rapid_length, const SimulateOptions& options,
                        const std::function<void(double)>& progress = {});
// The grid options (r, h, spacing, max_samples, loops, rim_band) a simulation with `options` samples on.
SurfaceGridOptions surface_grid_options(const SimulateOptions& options);

}  // namespace scallop
