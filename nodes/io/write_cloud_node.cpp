#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/write_support.h"
#include "nodes/types/ply_writer.h"
#include "nodes/types/cloud.h"

namespace scallop::io_nodes {

NodeDecl make_write_cloud_node() {
  NodeDecl d;
  d.type = "io.write_cloud";
  d.version = 2;  // 2: path relative to the output folder, and kept inside it
  d.description = "writes a cloud as PLY (x y z [nx ny nz] as double), binary little-endian or ascii";
  // Writing a file is a side effect, so nothing is gained by keeping the result on disk.
  d.cache_on_disk = false;
  d.input("cloud", "Cloud", "the points to write")
      .output("file", "File", "the written file")
      .param_output_path("path", "the PLY file to write (required), relative to the output folder (-o); "
                                 "a path that would leave it ('../x', '/abs') is refused")
      .param_bool("binary", true, "binary little-endian PLY; false for ascii");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    const std::string param = ctx.text("path");
    if (param.empty()) throw NodeError("parameter 'path' is empty: give the file to write");
    const bool binary = ctx.flag("binary");
    ctx.set("file", io::write_output_file(ctx, param, [&](const std::string& path) { write_ply(path, *cloud, binary); }));
  };
  return d;
}

}  // namespace scallop::io_nodes
