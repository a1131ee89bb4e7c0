#include "nodes/io/read_mesh.h"

#include "nodes/io/mesh_reader.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_support.h"

namespace scallop {

Mesh read_mesh(const std::string& path, double scale) {
  io::check_scale(path, scale);
  const std::string ext = io::lower_extension(path);
  const auto what = io::MeshRead::Mesh;
  Mesh mesh;
  if (ext == ".ply") mesh = read_ply_mesh(path, what);
  else if (ext == ".off") mesh = read_off(path, what);
  else if (ext == ".obj") mesh = read_obj(path, what);
  else if (ext == ".stl") mesh = read_stl(path, what);
  else
    io::fail(path, (ext.empty() ? std::string("file name has no extension") : "unsupported extension '" + ext + "'") +
                       " (expected .ply .off .obj .stl)");
  if (mesh.num_faces() == 0)
    io::fail(path, "no faces (" + std::to_string(mesh.num_vertices()) + (mesh.num_vertices() == 1 ? " vertex" : " vertices") +
                       "): a point cloud, not a mesh; read it with io.read_cloud");
  if (scale != 1.0)
    for (auto& p : mesh.vertices) p *= scale;
  return mesh;
}

}  // namespace scallop
