// PCD (Point Cloud Library) point reader.
#pragma once

#include <string>

#include "nodes/types/cloud.h"

namespace scallop {

// Reads a PCD file, v0.7 or the older v0.6-like headers (COUNT optional, default 1; POINTS
// optional, default WIDTH*HEIGHT; COLUMNS accepted for FIELDS). DATA may be
//   ascii              one point per line
//   binary             points one after another (array of structures), little-endian
//   binary_compressed  uint32 compressed size, uint32 uncompressed size, then an LZF block that
//                      holds each field for all points, one field after another (structure of arrays)
// Fields x y z are required; normal_x normal_y normal_z, when all three are present, become the
// normals; other fields (intensity, rgb, curvature, padding '_') are dropped. Points with NaN
// coordinates are kept (PCL writes NaN for missing points of an organised cloud).
// Returns P #P by 3 positions in the file's units, N #P by 3 or empty.
// Throws CloudReadError naming the line (header, ascii data) or byte offset (binary data).
PointCloud read_pcd(const std::string& path);

}  // namespace scallop
