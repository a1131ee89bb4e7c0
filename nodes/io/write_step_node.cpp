#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/write_step.h"
#include "nodes/io/write_support.h"
#include "nodes/types/document.h"
#include "nodes/types/surfaces.h"

namespace scallop::io_nodes {

NodeDecl make_write_step_node() {
  NodeDecl d;
  d.type = "io.write_step";
  d.version = 2;
  d.description =
      "writes fitted B-spline patches as a STEP file (AP214, mm; faces sewn along shared borders) that CAD tools "
      "open, and reads it back to check";
  // Writing a file is a side effect, so nothing is gained by keeping the result on disk.
  d.cache_on_disk = false;
  d.input("surfaces", "Surfaces", "the patches (surface.fit_bspline)")
      .output("file", "File", "the written file")
      .output("report", "Report", "{file_faces, faces, bspline_faces, shells, free_edges}: the faces in the file, and the file as OpenCASCADE reads it back (faces after its shape healing)")
      .param_output_path("path", "the file to write (required, .step or .stp), relative to the output folder (-o); a "
                                 "path that would leave it is refused");
  d.options<WriteStepOptions>()
      .flag("sew", &WriteStepOptions::sew, "sew the faces along the borders they share into shells")
      .number("sewing_tolerance", &WriteStepOptions::sewing_tolerance, 1e-7, 10, "mm",
              "borders closer than this are sewn into one edge");
  d.run = [](NodeContext& ctx) {
    auto surfaces = ctx.input<Surfaces>("surfaces");
    const std::string param = ctx.text("path");
    if (param.empty()) throw NodeError("parameter 'path' is empty: give the file to write");
    const WriteStepOptions o = ctx.options<WriteStepOptions>();
    StepSummary back;
    ctx.set("file", io::write_output_file(ctx, param, [&](const std::string& path) {
              write_step(*surfaces, path, o);
              back = read_step_summary(path);
            }));
    if (back.file_faces != surfaces->patches.size())
      throw NodeError("the STEP file holds " + std::to_string(back.file_faces) + " faces, not the " +
                      std::to_string(surfaces->patches.size()) + " patches written");
    if (back.faces != back.file_faces)
      ctx.warn("OpenCASCADE's reader splits the file's " + std::to_string(back.file_faces) + " faces into " +
               std::to_string(back.faces) + " (its shape healing cuts a patch that pinches or twists); the file holds "
               "one face per patch");
    Report r;
    r.data = {{"file_faces", back.file_faces}, {"faces", back.faces}, {"bspline_faces", back.bspline_faces},
              {"shells", back.shells}, {"free_edges", back.free_edges}};
    ctx.set("report", std::move(r));
  };
  return d;
}

}  // namespace scallop::io_nodes
