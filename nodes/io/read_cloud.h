// Reading a point cloud from a file, whatever its format.
#pragma once

#include <stdexcept>
#include <string>

#include "nodes/types/cloud.h"

namespace scallop {

// A file that cannot be read as a point cloud. what() names the file and where it broke:
//   "<path>: line <n>: <what>"    text formats and headers (lines count from 1)
//   "<path>: byte <offset>: <what>"  binary data (offset from the start of the file)
//   "<path>: <what>"              the file as a whole (missing, empty, unknown extension)
// Item numbers in messages (vertex 12, point 3, face 0) count from 0, as indices do in the files.
struct CloudReadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Reads the points (and normals, when the file has them) of the file at `path`, chosen by its
// extension, case-insensitive:
//   .ply                    PLY ascii / binary little- and big-endian   (read_ply)
//   .pcd                    PCD ascii / binary / binary_compressed       (read_pcd)
//   .xyz .txt .csv .pts     text columns x y z [nx ny nz ...]            (read_text_cloud)
//   .off .obj .stl          the vertices of a mesh                       (read_mesh_vertices)
// Every coordinate is multiplied by `scale` (e.g. 1000 for a file in metres); normals are not.
// Points with NaN coordinates are kept. A valid file with no points gives an empty cloud.
// Throws CloudReadError for a missing or malformed file, an unsupported extension or a scale
// that is not positive and finite.
PointCloud read_cloud(const std::string& path, double scale = 1.0);

}  // namespace scallop
