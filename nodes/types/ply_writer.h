// PLY writers for point clouds and meshes.
#pragma once

#include <string>

#include "nodes/types/cloud.h"
#include "nodes/types/mesh.h"

namespace scallop {

// Writes `cloud` as PLY with one 'vertex' element of double properties x y z, plus nx ny nz when
// the cloud has normals and `uncertainty` (mm) when it has per-point uncertainties. binary: binary_little_endian (exact); otherwise ascii with the shortest
// decimal form that reads back to the same double (also exact). NaN is written as "nan".
// Throws std::runtime_error "cannot write '<path>': <reason>" when the file cannot be written,
// or when the cloud has normals but not one per point.
void write_ply(const std::string& path, const PointCloud& cloud, bool binary = true);

// Writes `mesh` as binary little-endian PLY: element vertex (double x y z, plus nx ny nz when it
// has normals), element face (list uchar uint vertex_indices, plus int label when it has labels),
// and element edge (uint vertex1 vertex2, uchar feature = 1) when it has feature edges, the form
// ../shared/tools/compare_mesh.py and most mesh tools read. Throws std::runtime_error
// "cannot write '<path>': <reason>" when the file cannot be written or a face has over 255 corners.
void write_mesh_ply(const std::string& path, const Mesh& mesh);

}  // namespace scallop
