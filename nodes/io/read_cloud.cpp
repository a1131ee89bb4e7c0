#include "nodes/io/read_cloud.h"

#include "nodes/io/mesh_reader.h"
#include "nodes/io/pcd_reader.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_support.h"
#include "nodes/io/text_cloud_reader.h"

namespace scallop {

PointCloud read_cloud(const std::string& path, double scale) {
  io::check_scale(path, scale);
  const std::string ext = io::lower_extension(path);
  PointCloud cloud;
  if (ext == ".ply") cloud = read_ply(path);
  else if (ext == ".pcd") cloud = read_pcd(path);
  else if (ext == ".xyz" || ext == ".txt" || ext == ".csv") cloud = read_text_cloud(path);
  else if (ext == ".pts") cloud = read_text_cloud(path, false);
  else if (ext == ".off" || ext == ".obj" || ext == ".stl") cloud = read_mesh_vertices(path);
  else
    io::fail(path, (ext.empty() ? std::string("file name has no extension") : "unsupported extension '" + ext + "'") +
                       " (expected .ply .pcd .xyz .txt .csv .pts .off .obj .stl)");
  if (scale != 1.0)
    for (auto& p : cloud.points) p *= scale;
  return cloud;
}

}  // namespace scallop
