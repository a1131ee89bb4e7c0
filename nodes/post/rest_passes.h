// Rest machining (issue 14): the places of a part that every setup's passes still leave over the
// scallop limit, or uncut, cut again from a setup whose axis reaches them.
//
// The places are found as post.simulate_part finds them (part_samples.h, CentreIndex::trace): a
// sample is left when the ball tangent there reaches it (verify_part.py's test), it is not on the
// base, and the material over it is more than 0.8 h. Around each sample over 0.65 h, and around
// the highest of the others (3000 or 1 %), a 5 x 5 grid a fifth of the spacing apart is traced
// too: a cusp's crest may pass between samples.
//
// Each left place goes to the setup whose axis a makes the largest n . a (at least
// min_normal_dot) among those from which the ball tangent there goes straight up along a, r -
// tolerance clear of the part (tolerance = part_clearance_tolerance(e)): a 3-axis tool comes down
// that way (a refinement sample takes its seed's setup). A place none comes down to goes to the
// setup facing it best (n . a >= 0.5), whose rows come as near as the ball goes; and up to
// max_new_setups new clampings are added, each along the direction of a 2000-point lattice that
// comes down to the most of such places, while one comes down to any. What is left after that is
// reported (unreached).
//
// In a setup's machine frame a raster of balls covers its left places' ball centres: rows along
// x, `pitch` apart in y (0.9 sqrt(8 r h) times the smallest n_z of those places, at least a
// quarter of it), balls sqrt(8 r tolerance) apart along a row (the sagitta of a ball's path over
// a sharp convex edge, radius r, is then at most the tolerance); each ball comes down along -z
// from above the part until it touches it (the drop-cutter: it touches nothing else), and the
// rows are kept off the part like every pass (keep_off_part.h). What is left is traced again
// against the new passes; up to `rounds` rounds, the pitch halved each time, while the left area
// falls by a tenth or more. A dropped ball is kept only where it rests on the outside of the face
// it touches: through a hole in the mesh (a cloud's reconstruction has them) it would fall onto
// the inside of the part's far side (inside_drops counts those).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/surface/setups.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct RestOptions {
  double tool_radius = 0;  // r (mm)
  double scallop = 0;      // h (mm)
  double chord = 0;        // e (mm)
  Eigen::Vector3d base_normal = Eigen::Vector3d::Zero();  // outward normal of the base; 0: no base
  double base_angle = 10;          // degrees
  int rounds = 3;                  // 0: no rest passes
  double min_normal_dot = 0.05;    // the steepest place a setup is asked to reach
  std::size_t max_samples = 1500000;  // as the certificate's
  int max_new_setups = 2;          // clampings added for places no setup comes down to
  std::function<void(double, const std::string&)> progress;  // optional: the fraction done, what
};

struct RestResult {
  std::vector<std::size_t> passes;   // per setup, rest passes added (after keeping them off the part)
  std::vector<double> length;        // per setup, their ball centres' length (mm)
  int rounds = 0;                    // rounds made
  std::size_t new_setups = 0;        // clampings added (the last ones of `setups`)
  std::vector<Setup> added_setups;   // post.setup_programs: those clampings
  double spacing = 0;                // the samples' spacing (mm)
  double measured_area = 0;          // mm²: not base, reachable
  double left_area_before = 0;       // mm² left over 0.8 h (or uncut) by the setups' own passes
  double left_area_after = 0;        // mm² still left after the rest passes
  double unreached_area = 0;         // mm² of that no setup's axis comes down to
  std::vector<Eigen::Vector3d> unreached_at;  // up to 10 such places (part frame), 2 r apart
  // the search for new clampings ended because no direction of its lattice came down to any of
  // the places left (not because max_new_setups were added): another clamping would not help
  bool no_direction_left = false;
  std::size_t inside_drops = 0;      // balls left out: they came to rest on the inside of a face
};

// part    the whole part in its own frame, faces outward (closed or open)
// setups  the clampings (rotation, translation; axis in the part frame); new ones are appended
// cuts    per setup, its passes in its machine frame, already kept off the part; the rest passes
//         are appended to them (machine frame, kept off the part), and a cut per new setup
// part_distance  the distance balls are kept off in the part frame (the part's faces with the points
//         it holds and the places kept out: MeshDistance::with_points); null: the faces alone
// Throws std::invalid_argument for r <= 0, h <= 0, h >= r, or cuts and setups of different counts.
RestResult add_rest_passes(const Mesh& part, std::vector<Setup>& setups, std::vector<Toolpath>& cuts,
                           const RestOptions& options, const MeshDistance* part_distance = nullptr);

}  // namespace scallop
