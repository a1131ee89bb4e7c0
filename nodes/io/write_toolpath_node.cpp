#include <stdexcept>

#include "engine/node.h"
#include "engine/output_path.h"
#include "nodes/io/write_toolpath.h"
#include "nodes/types/document.h"
#include "nodes/types/toolpath.h"

namespace scallop::io_nodes {
NodeDecl make_write_toolpath_node() {
  NodeDecl d;
  d.type = "io.write_toolpath";
  d.version = 2;  // 2: path relative to the output folder, and kept inside it
  d.description = "writes the passes as JSON or CSV (contact, normal, tool tip per point)";
  d.cache_on_disk = false;
  d.input("path", "Toolpath", "the passes")
      .output("report", "Report", "what was written: file, format, passes, points")
      .param_output_path("path", "file to write, relative to the output folder (-o); a path that would leave "
                                 "it ('../x', '/abs') is refused")
      .param_choice("format", "json", {"json", "csv"}, "json: nested passes; csv: pass,index,cx,cy,cz,nx,ny,nz,tx,ty,tz");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<Toolpath>("path");
    std::string file = ctx.text("path"), format = ctx.text("format");
    if (file.empty()) throw NodeError("parameter 'path' (the file to write) is empty");
    try {
      file = output_file(ctx.output_dir(), file);
    } catch (const std::invalid_argument& e) {
      throw NodeError("parameter 'path': " + std::string(e.what()));
    }
    try {
      write_toolpath(*path, file, format);
    } catch (const std::exception& e) {
      throw NodeError(e.what());
    }
    std::size_t points = 0;
    for (const auto& p : path->passes) points += p.contact.size();
    Report r;
    r.data = {{"file", file}, {"format", format}, {"passes", path->passes.size()}, {"points", points}};
    ctx.set("report", std::move(r));
  };
  return d;
}
}  // namespace scallop::io_nodes
