// Reading the vertices of a mesh file (OFF, OBJ, STL) as a point cloud.
#pragma once

#include <string>

#include "nodes/types/cloud.h"

namespace scallop {

// OFF: header "OFF" (or COFF, NOFF, CNOFF) alone on its line or followed by the counts
// "nv nf [ne]" on the same line; then nv vertex lines "x y z [extra]" (NOFF: "x y z nx ny nz"),
// then nf polygon lines "k i_1 .. i_k [colour]" with any k. The faces are checked (indices in
// range) but dropped. '#' starts a comment. NOFF normals become the cloud's normals.
PointCloud read_off_vertices(const std::string& path);

// OBJ: the 'v x y z [w | r g b]' lines, in order; every other line is ignored (OBJ normals are
// per face corner, not per vertex, so none are returned).
PointCloud read_obj_vertices(const std::string& path);

// STL, binary or ascii (told apart by size and content, since some binary files also start with
// "solid"). Triangle corners are welded: corners with exactly equal coordinates become one vertex,
// numbered in order of first appearance. No normals (STL's are per facet).
PointCloud read_stl_vertices(const std::string& path);

// Dispatches on the extension: .off .obj .stl (case-insensitive).
// Returns P #V by 3 positions in the file's units. Throws CloudReadError.
PointCloud read_mesh_vertices(const std::string& path);

}  // namespace scallop
