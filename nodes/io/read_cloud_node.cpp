#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/read_cloud.h"
#include "nodes/types/cloud.h"

namespace scallop {

NodeDecl make_read_cloud_node() {
  NodeDecl d;
  d.type = "io.read_cloud";
  d.version = 1;
  d.description = "reads points (and normals, when present) from PLY, PCD, XYZ/CSV/TXT/PTS, or the vertices of OFF/OBJ/STL";
  d.input("file", "File", "the cloud file; the format is chosen by its extension")
      .output("cloud", "Cloud", "the points, NaN points kept, normals only when the file has them")
      .param_float("scale", 1.0, 1e-9, 1e9, "", "multiplies every coordinate, e.g. 1000 for a file in metres");
  d.run = [](NodeContext& ctx) {
    auto file = ctx.input<FileRef>("file");
    try {
      ctx.set("cloud", read_cloud(file->path, ctx.number("scale")));
    } catch (const CloudReadError& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop
