// Gouge guard: every planned ball position, and the middle of every move, is checked against the
// cloud's surface; where the surface would come inside the ball, the ball is lifted until it only
// touches it.
//
// A planner works on its own model of the surface (path.isoparametric: a fit of x, y, z over the
// (u, v) map). Where that model is poor (a fit that straddles a re-entrant corner of the outline,
// where the map squeezes a narrow spike, at a sparse steep rim) a contact point can be off the
// surface by more than the chord budget and the ball cuts into the part. The guard measures each
// ball centre c against independent witnesses: the height field fitted to the cloud in xy
// (HeightFieldModel, what post.simulate certifies against), via the foot point of c on it, and
// sampled with its uncertainty above every cloud point near c (the foot search finds one nearest
// place; the uncertainty may peak at another: a crest's top beside the flank the ball touches);
// where the foot lies more than half a spacing from its nearest point (beyond the cloud's edge the
// uncertainty grows outward faster than the ball's distance), also around the foot, half a
// spacing and one spacing away; and the cloud's points themselves within r of c.
// clearance(c) = distance to the surface − r, and the ball must clear the surface by its
// uncertainty δ there (0 on a clean cloud; grown beyond the cloud's edge, where the field is
// extrapolated): the real surface may be δ higher. A position
// reaching more than `tolerance` into that band (δ − clearance > tolerance; by default e/4 plus
// the reach the planner's chord budget leaves there, min(δ, 0.65 e − 0.15 δ), step_size.h) is lifted along +z
// until it clears it by δ (what post.simulate's gouge bound counts; where the surface is known
// worse than 6 e the gouge budget 0.9 e − 0.15 δ is itself a clearance, and the ball clears the
// band by 1.5 times that), and a move whose quarter
// points (and points 0.5 mm apart on longer moves) reach more than chord_tolerance into it (by
// default the gouge budget there, 0.9 e − 0.15 δ, step_size.h) gets a point inserted at its worst one,
// raised until it reaches in by 3/4 of that (and its halves are checked again, up to max_splits
// times); a move still too deep after that
// is raised whole, both ends, until its probes clear. A lifted ball leaves stock: the report
// says where and how much, so a planner's weak spot is never hidden. A planned ball that reaches
// into the points the trim left out (a wall beside a floor) is first moved sideways off them and
// set down on the patch again, at most r: it then finishes the patch up to where the ball last
// reaches it (pushed_off_left_out in the report); where that does not clear them it is lifted.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "nodes/geom/height_field_model.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/outline.h"
#include "nodes/geom/surface_band.h"
#include "nodes/types/toolpath.h"

namespace scallop {

// Clearance of a ball of radius r against a cloud's surface.
class BallClearance {
 public:
  // surface  the height field of `points`; points  the cloud (mm); outline  optional: the patch's
  // outline in xy (post.simulate's, from the boundary loops): a foot point inside it is on the
  // surface however far from the points (a gap between rim points that the certificate counts).
  // band  optional: surface_band(surface, points), when it is at hand (cached); computed here
  // otherwise. rim_band  with an outline: a foot point up to this far off the patch in xy
  // (beyond its outer loop or into a hole) is on the surface too (mm; the band path.isoparametric's band passes cut and
  // post.simulate counts). left_out  optional: points of the part that are not machined (what
  // cloud.trim_steep left out: a steep wall beside the patch, a piece apart); the ball clears
  // each of them, and off the patch, where such a point is nearer in xy than the cloud's, the
  // height field is not extrapolated (no foot there). All must outlive this.
  BallClearance(const HeightFieldModel& surface, const std::vector<Eigen::Vector3d>& points, double r,
                const Outline* outline = nullptr, const SurfaceBandView* band = nullptr, double rim_band = 0,
                const std::vector<Eigen::Vector3d>* left_out = nullptr);
  ~BallClearance();
  BallClearance(const BallClearance&) = delete;
  BallClearance& operator=(const BallClearance&) = delete;

  struct Result {
    double clearance = INFINITY;  // mm: distance from the centre to the surface − r (< 0: gouge)
    Eigen::Vector3d foot;         // nearest surface point found (valid when on_surface)
    Eigen::Vector3d normal;       // its upward unit normal (valid when on_surface)
    bool on_surface = false;      // the foot point lies on the patch, in the band beyond its
                                  // outermost points where the part's edge lies, or inside
                                  // the outline
    double uncertainty = 0;       // mm the surface there may be off the real one (on_surface)
    // How far the ball reaches into the band over the height field (raised by its uncertainty)
    // sampled above the cloud's points near it (mm, > 0: too deep; -inf: none within reach),
    // and the upward part of the unit direction from the deepest such sample to the centre.
    double band_reach = -INFINITY;
    double band_up = 1;
    // Whether the deepest band witness is a point left out (BallClearance's left_out), and which.
    bool left_out_deepest = false;
    Eigen::Vector3d left_out_at = Eigen::Vector3d::Zero();
    // How far the ball reaches into the band at its foot point, and by either witness (mm, > 0:
    // too deep); which of them reaches deeper (the direction a lift takes).
    double foot_reach() const { return (on_surface ? uncertainty : 0.0) - clearance; }
    double reach() const { return std::max(band_reach, foot_reach()); }
    bool band_is_deepest() const { return band_reach >= foot_reach(); }
  };
  // centre  ball centre; hint  a surface point near the contact (where the foot search starts).
  // Thread-safe.
  Result operator()(const Eigen::Vector3d& centre, const Eigen::Vector3d& hint) const;
  // The surface's sampling step (mm): HeightFieldModel::spacing.
  double spacing() const;
  // The cloud it checks against and its k-d tree by xy (leaf size 16), for other searches of
  // the same points (post.link's), so that they need not build their own.
  const std::vector<Eigen::Vector3d>& points() const;
  const KdTree<Eigen::Vector3d, 2>& xy_tree() const;
  // The patch's outline it was given, or null.
  const Outline* outline() const;
  // The points not machined it was given (empty when none).
  const std::vector<Eigen::Vector3d>& left_out() const;

 private:
  struct Impl;
  Impl* impl_;
};

struct GougeGuardOptions {
  double tolerance = 0;        // mm a planned position may reach in before it is lifted;
                               // <= 0: e/4 + chord_budget(e, δ).reach
  double chord_tolerance = 0;  // mm a move may reach in before a point is inserted; <= 0: the
                               // gouge budget where it reaches deepest, 0.9 e − 0.15 δ (the planner's)
  int max_splits = 3;          // how often a move may be halved
  std::function<void(double)> progress;
};

struct GougeGuardResult {
  Toolpath path;
  nlohmann::json report;
};

// Throws std::invalid_argument for a path without points, r <= 0 or mismatched normals, and
// std::runtime_error (saying where) when a ball would have to be lifted by more than 3 tool
// radii: such a plan does not follow the surface there, and lifting it only hides that. Where the
// ball reaches beyond the clearance's outline the message says how far: there the surface is
// only extrapolated, and a region left out beside the patch (a steep wall the trim cut off
// beside a floor) rises.
GougeGuardResult guard_gouges(const Toolpath& path, const BallClearance& clearance,
                              const GougeGuardOptions& options);

}  // namespace scallop
