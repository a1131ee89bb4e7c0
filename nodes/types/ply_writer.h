// PLY writer for point clouds.
#pragma once

#include <string>

#include "nodes/types/cloud.h"

namespace scallop {

// Writes `cloud` as PLY with one 'vertex' element of double properties x y z, plus nx ny nz when
// the cloud has normals and `uncertainty` (mm) when it has per-point uncertainties. binary: binary_little_endian (exact); otherwise ascii with the shortest
// decimal form that reads back to the same double (also exact). NaN is written as "nan".
// Throws std::runtime_error "cannot write '<path>': <reason>" when the file cannot be written,
// or when the cloud has normals but not one per point.
void write_ply(const std::string& path, const PointCloud& cloud, bool binary = true);

}  // namespace scallop
