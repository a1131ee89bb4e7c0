// PLY (Stanford polygon file) reader: points, or a polygon mesh.
#pragma once

#include <string>

#include "nodes/io/read_support.h"
#include "nodes/types/cloud.h"
#include "nodes/types/mesh.h"

namespace scallop {

// Reads the vertices of a PLY file: format ascii 1.0, binary_little_endian 1.0 or
// binary_big_endian 1.0. The vertex element must have x y z properties (any scalar type:
// char/uchar/short/ushort/int/uint/float/double or int8..float64); nx ny nz, when all three are
// present, become the normals. Other vertex properties (colour, confidence, list properties) and
// other elements before or after the vertices (face, range_grid, ...) are read past and dropped;
// 'comment' and 'obj_info' lines are ignored.
// Returns P #V by 3 positions in the file's units, N #V by 3 or empty.
// Throws CloudReadError naming the line (header, ascii data) or byte offset (binary data).
PointCloud read_ply(const std::string& path);

// The same file as a mesh. MeshRead::Vertices gives what read_ply gives; MeshRead::Mesh also
// reads the 'face' element: its list property 'vertex_indices' (or 'vertex_index', of an integer
// type) gives each face's corners (at least 3, each below the vertex count), a scalar 'label'
// the face labels; and an 'edge' element with vertex1, vertex2 and feature properties (the form
// write_mesh_ply writes) gives the feature edges, those whose feature is not 0. NaN and infinite
// vertex coordinates are refused. Errors name the line or byte as read_ply's do, e.g.
// "<path>: line 14: face 2 has index '8' but there are 8 vertices".
Mesh read_ply_mesh(const std::string& path, io::MeshRead what);

}  // namespace scallop
