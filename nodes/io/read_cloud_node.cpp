#include "engine/node.h"
#include "nodes/io/mm_units.h"
#include "nodes/io/read_cloud.h"
#include "nodes/io/read_input.h"
#include "nodes/types/cloud.h"

namespace scallop::io_nodes {

NodeDecl make_read_cloud_node() {
  NodeDecl d;
  d.type = "io.read_cloud";
  d.version = 2;  // 2: coordinates beyond 1e9 mm refused, a cloud that does not look like mm warned
  d.description = "reads points (and normals, when present) from PLY, PCD, XYZ/CSV/TXT/PTS, or the vertices of OFF/OBJ/STL";
  d.input("file", "File", "the cloud file; the format is chosen by its extension")
      .output("cloud", "Cloud", "the points, NaN points kept, normals only when the file has them")
      .param_float("scale", 1.0, 1e-9, 1e9, "", "multiplies every coordinate, e.g. 1000 for a file in metres");
  d.run = [](NodeContext& ctx) {
    std::string path;
    PointCloud cloud = io::read_input(ctx, read_cloud, path);
    check_units(ctx, path, cloud.points);
    ctx.set("cloud", std::move(cloud));
  };
  return d;
}

}  // namespace scallop::io_nodes
