#include <vector>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/write_mesh.h"
#include "nodes/io/write_support.h"
#include "nodes/types/mesh.h"

namespace scallop::io_nodes {

NodeDecl make_write_mesh_node() {
  NodeDecl d;
  d.type = "io.write_mesh";
  d.version = 1;
  d.description = "writes a mesh as PLY (binary, with normals, face labels and feature edges), OFF, OBJ or binary STL";
  // Writing a file is a side effect, so nothing is gained by keeping the result on disk.
  d.cache_on_disk = false;
  d.input("mesh", "Mesh", "the mesh to write")
      .output("file", "File", "the written file")
      .param_output_path("path", "the file to write (required), relative to the output folder (-o); a path that "
                                 "would leave it ('../x', '/abs') is refused")
      .param_choice("format", "auto", {"auto", "ply", "off", "obj", "stl"},
                    "auto: from the extension of path (.ply .off .obj .stl); STL is binary, its polygons "
                    "fan-triangulated; only PLY keeps face labels and feature edges");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    const std::string param = ctx.text("path");
    if (param.empty()) throw NodeError("parameter 'path' is empty: give the file to write");
    std::string format = ctx.text("format");
    if (format == "auto") {
      format = mesh_format_of(param);
      if (format.empty())
        throw NodeError("parameter 'path': '" + param +
                        "' has no mesh extension (.ply .off .obj .stl); give one, or set 'format'");
    }
    // Say what the format cannot hold rather than drop it without a word.
    std::vector<std::string> lost;
    if (format != "ply" && mesh->has_labels()) lost.push_back("face labels");
    if (format != "ply" && !mesh->feature_edges.empty()) lost.push_back("feature edges");
    if ((format == "obj" || format == "stl") && mesh->has_normals()) lost.push_back("vertex normals");
    if (!lost.empty()) {
      std::string what = lost[0];
      for (std::size_t i = 1; i < lost.size(); ++i) what += (i + 1 == lost.size() ? " and " : ", ") + lost[i];
      ctx.warn(format + " keeps no " + what + ": they are not in '" + param + "' (PLY keeps them)");
    }
    ctx.set("file", io::write_output_file(ctx, param, [&](const std::string& path) { write_mesh(*mesh, path, format); }));
  };
  return d;
}

}  // namespace scallop::io_nodes
