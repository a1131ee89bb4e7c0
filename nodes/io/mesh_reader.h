// Reading OFF, OBJ and STL files as polygon meshes, or only their vertices as a point cloud
// (PLY: ply_reader.h).
#pragma once

#include <string>

#include "nodes/io/read_support.h"
#include "nodes/types/cloud.h"
#include "nodes/types/mesh.h"

namespace scallop {

// OFF: header "OFF" (or COFF, NOFF, CNOFF) alone on its line or followed by the counts
// "nv nf [ne]" on the same line; then nv vertex lines "x y z [extra]" (NOFF: "x y z nx ny nz"),
// then nf polygon lines "k i_1 .. i_k [colour]" with any k. The indices are checked (in range)
// whatever `what`; MeshRead::Mesh keeps the faces (k >= 3). '#' starts a comment. NOFF normals
// become the vertex normals.
Mesh read_off(const std::string& path, io::MeshRead what);

// OBJ: the 'v x y z [w | r g b]' lines, in order; with MeshRead::Mesh also the 'f' lines, whose
// corners are "i", "i/t", "i//n" or "i/t/n": i counts the vertices from 1, or back from the last
// one read so far when negative (-1 is the last). Every other line (vn vt l g o usemtl s ...)
// is ignored: OBJ normals are per face corner, not per vertex, so none are returned.
Mesh read_obj(const std::string& path, io::MeshRead what);

// STL, binary or ascii (told apart by size and content, since some binary files also start with
// "solid"). Triangle corners are welded: corners with exactly equal coordinates become one vertex,
// numbered in order of first appearance (hashing, linear in the corners). Faces are the
// triangles over the welded vertices (a sliver whose corners weld together stays, with a
// repeated corner). No normals (STL's are per facet).
Mesh read_stl(const std::string& path, io::MeshRead what);

// The vertices of an .off .obj or .stl file (case-insensitive) as a point cloud, for
// io.read_cloud: P #V by 3 positions in the file's units, N #V by 3 (NOFF) or empty.
// Throws CloudReadError.
PointCloud read_mesh_vertices(const std::string& path);

}  // namespace scallop
