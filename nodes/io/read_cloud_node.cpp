#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/mm_units.h"
#include "nodes/io/read_cloud.h"
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
    auto file = ctx.input<FileRef>("file");
    const double scale = ctx.number("scale");
    PointCloud cloud;
    try {
      cloud = read_cloud(file->path, scale);
    } catch (const CloudReadError& e) {
      throw InputError(e.what());  // a malformed file is bad input: exit 2
    }
    if (auto bad = out_of_range_point(cloud.points); !bad.empty()) throw InputError(file->path + ": " + bad);
    if (auto w = units_warning(measure_scale(cloud.points), scale, ctx.node_id() + ".scale"); !w.empty()) ctx.warn(w);
    ctx.set("cloud", std::move(cloud));
  };
  return d;
}

}  // namespace scallop::io_nodes
