// Plain-text point reader (XYZ, CSV, TXT, PTS).
#pragma once

#include <string>

#include "nodes/types/cloud.h"

namespace scallop {

// Reads one point per line: x y z, or x y z nx ny nz followed by any further columns. Values are
// separated by blanks, or by commas or semicolons (blanks around them allowed; an empty field
// between two separators is an error, not skipped). Text after '#' is a comment. The first
// non-comment line may be a header that is not all numbers ("x,y,z,nx,ny,nz") or a single count
// (the first line of a .pts file); it is skipped. Every data line must have as many values as the
// first one. With 3 to 5 columns the cloud has no normals; with 6 or more, columns 4-6 are the
// normals unless `columns_4_to_6_are_normals` is false (a .pts file's columns 4-7 are intensity
// and colour).
// Returns P #P by 3 positions in the file's units, N #P by 3 or empty.
// Throws CloudReadError "<path>: line <n>: <what>" for a malformed line.
PointCloud read_text_cloud(const std::string& path, bool columns_4_to_6_are_normals = true);

}  // namespace scallop
