// A quad mesh of a part, aligned with its feature curves, by QuadriFlow (mesh.quad_remesh).
//
// papers/point-clouds-to-workpieces.md turns its triangle mesh into quads with QuadriFlow (Huang
// et al. 2018). Debian ships QuadriFlow inside Blender, so Blender is run headless as a child
// process: `blender -b --factory-startup --python script.py -- in out target seed`, where the
// script (kept in quad_remesh.cpp, written to a private temporary folder at run time) builds a
// Blender mesh from our file, calls bpy.ops.object.quadriflow_remesh(mode='FACES',
// target_faces, seed, use_preserve_sharp, use_preserve_boundary, use_mesh_symmetry=False) and
// writes the result. The two files are raw little-endian arrays of our own, not OBJ or PLY: no
// importer changes axes (Blender's OBJ and PLY importers turn Y up), triangulates or reorders.
// Blender holds coordinates as 32-bit floats, so the mesh goes over centred on its bounding box
// (the offset added back in double on return): the part's frame is kept exactly, positions to
// about 6e-8 of the part's size.
//
// Sharp features: QuadriFlow (as Blender 3.4 runs it) finds the edges it keeps sharp itself,
// from its triangles, where the two faces' normals differ by more than 60 degrees; Blender hands
// it only positions and triangles, so edges marked sharp in Blender change nothing (checked:
// marking every edge sharp gives the same output byte for byte). Feature curves softer than 60
// degrees are therefore not aligned with on purpose; the report gives their length.
//
// The output is checked and made to match the input's conventions. QuadriFlow writes a triangle
// of its output as a quad of no area, two opposite corners at one place on two vertices (a, b,
// a', c): such a doublet is zipped (a' welded to a, the face removed: its neighbours then share
// the edges a-b and a-c), so the rest stays all quads; a face with a corner repeating the one
// before loses the repeat (a quad becomes a triangle; two such triangles sharing an edge are
// made one quad, a lone one away from the border is taken out and closed as below: see
// pair_triangles). Unused vertices are dropped; each component is turned to the input's
// orientation when QuadriFlow reversed it (the area-weighted agreement of its face normals with
// the nearest input face's). Where QuadriFlow left a triangle
// out, a three-edge hole the input has not (a 40 x 30 x 12 box at 1500 quads: two, for every
// seed tried; the fandisk at 1000 quads: two), the holes are closed and the mesh kept all quads
// (fill_triangle_holes.h): a hole would pass for the part's border downstream. The result must
// lie near the input (quads_off_the_input), be manifold and consistently oriented, and have no
// more boundary loops than the input; otherwise the next seed is tried (options.tries), and then an error
// says what was wrong with each. Its feature edges are the
// sharp edges at options.angle_deg (sharp_edges.h).
//
// Snapping: QuadriFlow's vertices lie off the part near sharp features and corners (0.1 mm on
// the bundled domed block with 1.2 mm quads), so they are moved back onto the input, corners onto
// its corners and feature vertices onto its feature curves, each by at most the output's mean
// edge length (snap_to_reference.h); then the feature share is measured.
//
// Feature share, the fraction of the input's feature-curve length that lies on quad edges:
// the input's feature edges (its feature_edges when it has them, else its sharp edges at
// angle_deg) are cut into pieces of at most a quarter of the output's mean edge length h; a
// piece lies on quad edges when its midpoint is within feature_tolerance * h of a feature edge
// of the output. share = length of such pieces / feature length (1 when there are no features).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include "nodes/mesh/snap_to_reference.h"
#include "nodes/types/mesh.h"

namespace scallop {

struct QuadRemeshOptions {
  int target_faces = 4000;          // quads asked of QuadriFlow (it gives about as many)
  double target_edge_length = 0;    // mm; > 0: target_faces = area / length^2 instead
  int seed = 0;                     // QuadriFlow's random seed: the same seed, the same quads
  int tries = 6;                    // seeds tried (seed, seed + 1, ...) while the quads are not usable (the ABC plate's 200 000-point cloud: seed 4)
  double angle_deg = 50;            // an edge is sharp when its faces' normals differ by more
  double feature_tolerance = 0.1;   // of the output's mean edge length (feature share above)
  std::string blender;              // Blender's executable; "": $SCALLOP_BLENDER, else blender on PATH
  double timeout_s = 300;           // Blender is killed after this long, and the next try made
  bool snap = true;                 // move the quads' vertices onto the input (snap_to_reference.h)
};

struct QuadRemeshReport {
  std::size_t target_faces = 0;   // as asked of QuadriFlow
  std::size_t faces = 0, quads = 0, vertices = 0;
  double quad_fraction = 0;       // quads / faces
  std::size_t extraordinary_points = 0;  // interior vertices whose valence is not 4
  double mean_edge_length = 0;    // mm
  std::size_t doublets_zipped = 0;  // QuadriFlow's triangles written as quads of no area (see above)
  std::size_t holes_filled = 0, quads_split = 0;  // its triangles left out, closed (fill_triangle_holes.h)
  std::size_t repeated_corners_removed = 0, faces_dropped = 0, components_reversed = 0;
  // triangles left by a repeated corner: pairs sharing an edge made one quad; lone ones opened
  // into three-edge holes (closed with the holes above)
  std::size_t triangles_paired = 0, triangles_opened = 0;
  std::string feature_source;     // "feature_edges" (the input's) or "angle"
  double feature_length = 0;      // mm, the input's feature curves
  double feature_length_on_quad_edges = 0;  // mm
  double feature_share = 0;       // the ratio of the two
  double feature_tolerance_mm = 0;
  double feature_length_below_60 = 0;  // mm of the input's feature edges QuadriFlow does not see as sharp
  std::size_t sharp_edges = 0;    // the output's
  double seconds = 0;             // Blender's wall time
  double quadriflow_seconds = 0;  // of which in the remesher
  std::string blender_version;
  std::filesystem::path blender;  // the executable run
  int seed = 0;                   // the seed whose quads were used
  int seeds_tried = 1;            // 1 + the seeds whose quads were not usable (torn, not a manifold)
  SnapReport snap;                // the vertices moved onto the input (when options.snap)
  std::string warning;            // what the user must see, or empty (feature curves QuadriFlow does not keep)
};

// Blender is not installed or not where it was said to be: the message says how to get it.
struct BlenderMissing : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The Blender executable options.blender, $SCALLOP_BLENDER or PATH names; throws BlenderMissing
// ("needs Blender (QuadriFlow): install the Debian package blender ...; <what was looked for>").
std::filesystem::path find_blender(const std::string& blender_option);

// mesh      a manifold, consistently oriented polygon mesh (mesh.repair makes one), closed or with
//           boundaries (they are kept); faces counter-clockwise seen from outside
// progress  optional, fraction in [0, 1] and what is being done
// Returns the quad mesh: faces counter-clockwise seen from outside, feature_edges its sharp
// edges, no normals or labels. Throws std::invalid_argument naming what is wrong with the input
// (no faces, a repeated corner, non-manifold edge or vertex, inconsistent orientation: run
// mesh.repair), BlenderMissing, std::runtime_error when Blender fails (with its last lines of
// output), times out, or gives a mesh that is not manifold and consistently oriented or has holes
// the input has not.
Mesh quad_remesh(const Mesh& mesh, const QuadRemeshOptions& options, QuadRemeshReport& report,
                 const std::function<void(double, const std::string&)>& progress = {});

// Interior vertices (on no boundary edge, on some face) whose number of edges is not 4.
std::size_t extraordinary_points(const Mesh& mesh);

// What quad_remesh does to QuadriFlow's output first (see above): vertices of a face at one place
// welded (to the lower index), doublets (a, b, a, c) removed, a corner repeating the one before
// dropped, faces left with fewer than 3 corners dropped, unused vertices dropped (the others
// keep their order). Counts go to report.doublets_zipped, repeated_corners_removed, faces_dropped.
Mesh clean_quadriflow_output(const Mesh& quads, QuadRemeshReport& report);

// "" when `quads` has no more boundary loops than `input`, else the error quad_remesh throws:
// QuadriFlow tears a hole where it leaves out a triangle, which would pass for the part's border.
std::string holes_torn(const Mesh& input, const Mesh& quads);

// "" when every vertex of `quads` lies within 5 % of the input's bounding-box diagonal of that
// box, else the error quad_remesh throws, with the input's pieces, boundary loops and handles:
// QuadriFlow that does not converge scatters vertices hundreds of mm off the part (the ABC
// plate's cloud sampled inside its overlapping solids too: 8 pieces, 315 loops, 360 handles).
std::string quads_off_the_input(const Mesh& input, const Mesh& quads);

// quads  manifold, consistently oriented, quads and triangles (vertices, faces only)
// The triangles made quads where they can be: two sharing an edge become one quad (their four
// corners, in the triangles' direction); a lone one none of whose corners is on the border is
// taken out, leaving a three-edge hole for fill_triangle_holes. Triangles on the border stay.
// Counts them in report.triangles_paired and triangles_opened. A mesh without triangles comes
// back as it is; otherwise the merged quads come first, then the kept faces in order.
Mesh pair_triangles(const Mesh& quads, QuadRemeshReport& report);

// The reason `mesh` is not a manifold, consistently oriented polygon mesh, or "" when it is: no
// faces, a face with fewer than 3 corners, a corner past the vertices or repeated, an edge with 3
// or more faces, an edge both its faces run the same way, a vertex joining separate fans of faces
// (each with a count and the first where it happens).
std::string orientable_manifold_problem(const Mesh& mesh);

}  // namespace scallop
