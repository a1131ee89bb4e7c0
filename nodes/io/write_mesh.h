// Mesh export: PLY (the Mesh's own form), OFF, OBJ and STL.
#pragma once

#include <string>

#include "nodes/types/mesh.h"

namespace scallop {

// The mesh format named by the extension of `path` (case-insensitive): "ply", "off", "obj",
// "stl", or "" for any other.
std::string mesh_format_of(const std::string& path);

// Writes `mesh` to `path` as `format`:
//   ply  binary little-endian: vertices (double), vertex normals, faces with their labels, the
//        feature edges as an 'edge' element flagged 'feature' (write_mesh_ply)
//   off  ascii, "OFF" (or "NOFF" with vertex normals), coordinates in their shortest exact
//        decimal form, one "k i_1 .. i_k" line per face
//   obj  ascii 'v x y z' lines (exact, as OFF), 'f' lines counting vertices from 1
//   stl  binary: every face fan-triangulated from its first corner (a quad gives 2 triangles),
//        corners as float32, facet normal the unit normal of each triangle (0 0 0 for one
//        without area); STL has no shared vertices, normals, labels or feature edges
// Labels and feature edges are written by PLY only, vertex normals by PLY and OFF.
// Throws std::invalid_argument for an unknown format, std::runtime_error "cannot write '<path>':
// <reason>" when the file cannot be written.
void write_mesh(const Mesh& mesh, const std::string& path, const std::string& format);

}  // namespace scallop
