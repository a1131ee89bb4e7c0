// PLY (Stanford polygon file) point reader.
#pragma once

#include <string>

#include "nodes/types/cloud.h"

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

}  // namespace scallop
