// Clampings of a part: its patches grouped by machining direction into as few setups as the
// directions allow (issue 14; papers/point-clouds-to-workpieces.md machines each SHF along its
// own direction and groups the SHFs that share one).
//
// A patch can be cut in a setup of tool axis a (unit, part frame, from the part towards the
// spindle) when every normal of its surface (sampled on a 17 x 17 grid of its (u, v) square,
// turned to its direction) makes n . a >= t_p with it, or when a is the patch's own direction (a
// patch is a height field along it, however steep). t_p = min_normal_dot, lowered for a patch
// that no axis meets that well to half of its best (the largest smallest n . a over all
// candidates, at least 0.001): a steep strip along a rounded edge still joins a setup that meets
// it half as well as the best one could. Candidate axes: the patches' own directions, the axis
// straight away from the base when it is known (the part standing on it, cut from above) and the
// six coordinate axes: clampings square to the part's frame or to a patch, which a vise and an
// angle plate give; with any_axis also 2000 directions spread over the sphere (a Fibonacci
// lattice), for a fixture that tilts the part at compound angles (a box then needs 2 setups,
// not 5). The
// setups are chosen greedily (set cover): the candidate that can cut the most patches not yet
// covered, ties to the one whose smallest n . a over them is larger (a square axis, away from the
// base or along a coordinate axis, counted 0.005 better: a machinist sets it up without a
// protractor), then to the earlier candidate; repeated until every patch is covered. An axis reaches a patch only when the rays
// along it from the patch's samples (started 0.01 of the part's diagonal along the axis, past the
// gap between the fitted surface and the mesh) leave without meeting the part: an overhang hides
// it (the ball's width is the gouge guard's matter). A patch hidden from its own direction on
// more than a tenth of its samples (a bore's wall, whose own direction runs into the opposite
// wall) has that privilege moved to the direction of the 2000 over the sphere that reaches the
// most of its samples with n . a at least t_p (ties to the larger smallest n . a), when it reaches
// more than its own: tilted along the bore, from its end. Each patch then goes to the chosen
// setup where its smallest n . a is largest. Greedy set cover is within a factor ln(patches) of
// the fewest setups. Measured (graphs/mesh-to-surfaces.json, defaults): the fandisk's 65 patches
// in 14 setups (13 with any_axis), the block's 101 in 13 (11): thin strips along rounded edges,
// nearly vertical to every axis but their own, drive the count. With the part's mesh
// (graphs/mesh-workpiece-contour.json, r = 2, 2026-11-27): the block x 5's 104 patches in 25
// setups, 304 samples hidden from their setup's axis (33 setups and 6 186 before hidden patches
// were reached around the part).
//
// part_to_machine: a rotation R with R a = +z (the shortest rotation; a half turn about x when a =
// -z), and t such that the part's bounding box in the machine frame is centred on x = y = 0 and
// its lowest point is at z = 0 (the table). A part point p is at R p + t.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/types/mesh.h"
#include "nodes/types/surfaces.h"

namespace scallop {

struct SetupOptions {
  double min_normal_dot = 0.2;  // steepest surface a setup cuts besides its own patches: about 78 degrees
  bool any_axis = false;        // also 2000 axes spread over the sphere (clampings at compound angles)
};

// A patch the part hides in part from its setup's axis (the best found for it): those places
// cannot be reached from this clamping, and are left as stock.
struct HiddenPatch {
  std::uint32_t patch = 0;
  std::size_t samples = 0;  // of the 17 x 17 hidden
  Eigen::Vector3d at;       // their mean position, part frame
};

struct Setup {
  std::string name;                       // "1: +z", "2: -x", "3: (0.707, 0.000, 0.707)": order, axis
  Eigen::Vector3d axis;                   // unit tool axis, part frame
  Eigen::Matrix3d rotation;               // R
  Eigen::Vector3d translation;            // t
  std::vector<std::uint32_t> patches;     // indices into Surfaces::patches, increasing
  double min_normal_dot = 1;              // smallest n . axis over those patches
  std::size_t hidden_samples = 0;         // samples of those patches the axis cannot reach (see above)
  std::vector<HiddenPatch> hidden_patches;  // the patches they belong to
};

// part  the whole part (its mesh): where it hides a patch from an axis, and where it stands in
//       each setup; may be empty (no hiding, t = 0).
// Throws std::invalid_argument when there is no patch, an option is out of range, or a patch's
// surface or direction is not usable (naming the patch).
std::vector<Setup> plan_setups(const Surfaces& surfaces, const Mesh& part, const SetupOptions& options = {});

// part_to_machine as scallop-setups/1 writes it: 3 rows [R | t].
nlohmann::json part_to_machine(const Setup& setup);

// The setups as surface.setups reports them: [{name, axis, part_to_machine, patches,
// min_normal_dot, hidden_samples, hidden_patches: [{patch, samples, at}]}], and back (without
// hidden_patches). Reading throws std::invalid_argument for a malformed
// report (naming the setup), a part_to_machine whose R is not a rotation (|R^T R - I| > 1e-6 or
// det R < 0, as verify_part.py refuses it) or a patch index not below `patches`.
nlohmann::json setups_report(const std::vector<Setup>& setups);
std::vector<Setup> setups_from_report(const nlohmann::json& report, std::size_t patches);

// n directions spread evenly over the sphere (a Fibonacci lattice).
std::vector<Eigen::Vector3d> sphere_lattice(int n);

// The smallest rotation taking unit vector a to +z (a half turn about x for a = -z).
Eigen::Matrix3d rotation_to_z(const Eigen::Vector3d& a);

// The setup's rotation (rotation_to_z of its axis) and translation: the part's points (its
// vertices) centred on x = y = 0 in the machine frame, the lowest on z = 0 (t = 0 without points).
void place_setup(Setup& setup, const std::vector<Eigen::Vector3d>& part);

}  // namespace scallop
