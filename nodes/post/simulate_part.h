// The certificate of a whole part machined in several clampings (issue 14): what every setup's
// ball-end program leaves on the part's mesh, with the definitions of
// ../shared/tools/verify_part.py (README there), so that the product's verdict and that judge's
// can be compared number for number.
//
// Samples: every face of the mesh in strips parallel to its longest edge, about one sample per
// spacing² of area, each standing for its share (part_samples.h, as verify_part.py samples);
// normals the faces', outward (corners counter-clockwise seen from outside).
// - base: samples whose normal is within base_angle of base_normal sit on the table: not measured.
// - unreachable: a ball of radius r tangent at p (centre p + r n) comes nearer than r - tol to
//   the part elsewhere: not measured; reported with the largest radius that would reach it.
// - For every other sample p, with C the feed ball centres of all setups (part frame):
//     scallop = smallest t >= 0 with d(p + t n, C) <= r (the material no setup removed; exact,
//               as post.simulate), uncut when none by t = 20 h;
//   the surface known to ±delta (surface_uncertainty) makes it a bound: scallop + delta.
// - gouge (per setup): r - D(c) + delta over the feed ball centres c of the setup, D the signed
//   distance to the mesh (negative inside), the least along each move found by
//   MeshDistance::least_along (as verify_part.py): an upper bound, within 1e-5 mm of the truth
//   where it exceeds tol.
// - rapids: a rapid is through the part where D(c) - r < -tol anywhere along it (marched by the
//   clearance, which bounds how far it can fall).
// - interior: farther than `margin` from a border edge or an edge whose faces' normals differ
//   by more than feature_angle (verify_part.py's 30 degrees).
// pass (verify_part.py's rule): interior scallop max <= 1.01 h, gouge max <= tol, nothing uncut
// and no rapid through the part; tol = max(e, 0.001). The whole-part figures are reported beside.
// The 1000 highest scallops (or 1 %), and the highest of every cell of 32 spacings near the top
// (nodes/post/refinement_seeds.h), are refined with local grids down to 1/256 of the spacing.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "nodes/post/centre_index.h"
#include "nodes/types/mesh.h"
#include "nodes/types/simulation.h"

namespace scallop {

// One clamping's cut, taken back to the part's frame.
struct PartSetupCut {
  std::string name;
  std::vector<CentreSegment> feed;   // ball centres of the feed and plunge moves
  std::vector<CentreSegment> rapid;  // ball centres of the rapid moves
};

struct PartSimulateOptions {
  double tool_radius = 0;   // r (mm)
  double scallop = 0;       // h (mm)
  double chord = 0;         // e (mm): gouges up to max(e, 0.001) pass
  double surface_uncertainty = 0;  // delta (mm): how far the real part may lie off the mesh
  double spacing = 0;       // mm; 0: sqrt(8 r h) / 8, raised to stay within max_samples
  double margin = 0;        // mm; 0: sqrt(8 r h)
  // mm: how far the mesh's edges may lie off the part's (a mesh made from a cloud): the interior
  // starts this much nearer them, so that it holds all of the part's own interior
  double edge_uncertainty = 0;
  // the same in mean edge lengths of the part's mesh (a reconstruction's edges are about its
  // cloud's spacing, and its edges of the part can lie a spacing or more off, where the chamfer
  // was not restored in full); the larger of the two counts
  double edge_uncertainty_edges = 0;
  std::size_t max_samples = 1500000;
  Eigen::Vector3d base_normal = Eigen::Vector3d::Zero();  // outward normal of the base; 0: no base
  double base_angle = 10;     // degrees
  double feature_angle = 30;  // degrees
  // mm beyond r a ball centre must keep from the faces where `part` crosses itself
  // (tangle_keep_out's margin: < 0 its rule for a reconstruction, 0 none)
  double tangle_margin = -1;
  // Places no clamping's axis comes down to clear of the part (post.setup_programs' rest search,
  // part frame) and their area (mm²): a failing interior maximum within 2 r of one says so.
  std::vector<Eigen::Vector3d> unreached_at;
  double unreached_area = 0;
  bool unreached_by_any_direction = false;  // the search for clampings found no direction for them
};

// part   the part's mesh in its own frame, faces outward; closed or open (an open mesh: a ball
//        centre beyond a border may be taken for inside or outside by its nearest face).
// setups the cuts of every clamping, in the part frame.
// Returns the samples (with their faces), the limits and the report: pass, fail_reasons,
// scallop_max, scallop_p99, scallop_mean, frac_over_limit, uncut_fraction (and each _interior),
// gouge_max, rapids_through_part, rapid_min_clearance, cut_length, rapid_length, base_fraction,
// unreachable_fraction, measured_fraction, surface_area, samples, samples_measured,
// samples_interior, samples_refined, spacing, margin, surface_uncertainty, tool_radius,
// scallop_limit, chord_limit, setups [{name, cut_length, rapid_length, gouge_max, gouge_at (the
// ball centre there, part frame),
// rapids_through_part, finished_fraction}], unreachable [{x, y, z, reach_radius}] (up to 10
// places, 2 r apart, smallest reach first), worst [{x, y, z, kind, value, interior}] (up to 10,
// one per sqrt(8 r h): interior first, then by excess), scallop_max_interior_at {x, y, z} (the
// interior sample with the most material left; absent when none was cut).
// Throws std::invalid_argument for r <= 0, h <= 0, h >= r, a mesh without faces, no setup, no
// feed move at all, or a non-finite centre (naming the setup).
// outer  where given, gouge and rapids are measured against it instead of `part`: the part's outer
//        bound when the real part is only known to lie between two meshes (mesh.cloud_envelope).
//        Must have faces.
// inner  where given, `part` with its vertices moved (the same faces): the part's inner bound. Each
//        sample is still placed, classified (base, reach, interior) and reported on `part`, but
//        its scallop is traced from the same place of the inner mesh (same face, same barycentric
//        coordinates) along part's normal: the material left above the lowest the part may be.
// cloud  where given, the points the part was measured at (the cloud the mesh was made from): a
//        point inside a feed ball is material of the part cut away, whatever the meshes say (where
//        the part sticks out of its outer bound, at an edge left bevelled). The deepest,
//        r - (distance to the nearest feed centre), counts in gouge_max; the report adds
//        gouge_max_cloud, gouge_cloud_at {x, y, z} (the point) and cloud_points_cut (deeper than
//        the tolerance).
Simulation simulate_part(const Mesh& part, const std::vector<PartSetupCut>& setups, const PartSimulateOptions& options,
                         const std::function<void(double)>& progress = {}, const Mesh* outer = nullptr,
                         const Mesh* inner = nullptr, const std::vector<Eigen::Vector3d>* cloud = nullptr);

}  // namespace scallop
