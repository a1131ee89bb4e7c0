// Reading a polygon mesh from a file, whatever its format.
#pragma once

#include <string>

#include "nodes/io/read_cloud.h"
#include "nodes/types/mesh.h"

namespace scallop {

// Reads the mesh in the file at `path`, chosen by its extension, case-insensitive:
//   .ply   ascii / binary little- and big-endian; vertex normals, face labels and feature edges
//          when the file has them                                        (read_ply_mesh)
//   .off   OFF, COFF, NOFF (normals), CNOFF                              (read_off)
//   .obj   the v and f lines                                             (read_obj)
//   .stl   ascii or binary, coincident corners welded                    (read_stl)
// Every coordinate is multiplied by `scale` (e.g. 1000 for a file in metres); normals are not.
// Throws CloudReadError, its what() formed as read_cloud's ("<path>: line <n>: <what>",
// "<path>: byte <offset>: <what>", "<path>: <what>"), for a missing, empty or malformed file, a
// face with fewer than 3 corners or an index past the vertices, a NaN or infinite coordinate, a
// file with no faces, an unsupported extension or a scale that is not positive and finite.
Mesh read_mesh(const std::string& path, double scale = 1.0);

}  // namespace scallop
