// Closing the three-edge holes QuadriFlow tears into its quads, keeping the mesh all quads.
//
// QuadriFlow (as Blender runs it) leaves out the triangles of its output: a box of 40 x 30 x 12
// mm at 1500 quads comes back with two three-edge holes, one in its top, one in its bottom, for
// every seed tried (0 .. 3); the fandisk at 1000 quads likewise. A quad mesh cannot close a
// three-edge hole by itself (a disk of quads has an even border), so each hole is filled with a
// triangle and the triangles are turned into quads in pairs: a strip of faces is walked from one
// triangle to the nearest other (a closed mesh has an even number of triangles: 2E = 4Q + 3T),
// or, on a mesh with a border, to the border; the midpoint of each edge the strip crosses becomes
// a vertex, so both triangles gain a corner (quads) and each quad crossed gains two, splitting
// into two quads. The strip prefers to cross quads straight through (opposite edges: two clean
// quads); where it turns, the quad splits through its corner between the two edges, one of the
// two quads then having a straight angle at a midpoint.
#pragma once

#include <cstdint>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

struct TriangleHoleFill {
  std::size_t holes = 0;        // three-edge holes filled
  std::size_t quads_split = 0;  // quads crossed by the strips, each now two
  std::size_t left = 0;         // triangles no strip could reach (an odd number on a closed piece)
};

// mesh   manifold, consistently oriented, all quads (but for the holes)
// holes  boundary loops of `mesh` of three vertices each, as boundary_loops gives them
// Adds the filling triangles, pairs them by strips as above (to the border only where the mesh
// has other boundary edges), appends the midpoints as vertices; vertex normals, labels and
// feature edges are not kept (the mesh must have none). Faces are renumbered.
TriangleHoleFill fill_triangle_holes(Mesh& mesh, const std::vector<std::vector<std::uint32_t>>& holes);

}  // namespace scallop
