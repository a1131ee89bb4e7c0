#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/post/gcode.h"
#include "nodes/types/document.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_gcode_node() {
  NodeDecl d;
  d.type = "post.gcode";
  d.version = 1;
  d.description = "G-code of a linked path (XYZ = tool tip, mm, 4 decimals), optional G2/G3 arc fitting";
  d.input("path", "LinkedPath", "the linked machine moves")
      .input("source", "File", "the part's input file: its content hash goes into the header", false)
      .output("gcode", "GCode", "the program text");
  d.options<GCodeOptions>()
      .choice("dialect", &GCodeOptions::dialect, {"linuxcnc", "grbl", "fanuc"},
              "controller dialect: linuxcnc (M2), grbl (M2), fanuc (% framing, O-number, M30)")
      .number("feed", &GCodeOptions::feed, 1e-3, 1e6, "mm/min", "feed rate of cutting moves")
      .number("plunge_feed", &GCodeOptions::plunge_feed, 1e-3, 1e6, "mm/min", "feed rate of plunges")
      .number("spindle_rpm", &GCodeOptions::spindle_rpm, 0, 1e6, "rpm",
              "spindle speed (M3 S..); 0 writes no spindle words")
      .flag("arcs", &GCodeOptions::arcs, "replace runs of feed points lying on a circle (XY, XZ or YZ plane) by G2/G3")
      .number("arc_tolerance", &GCodeOptions::arc_tolerance, 0, 1, "mm",
              "largest distance between an arc and the points it replaces; 0: the chord error of the path (at least 0.001)")
      .integer("program_number", &GCodeOptions::program_number, 1, 9999, "", "fanuc O-number")
      .text("graph_name", &GCodeOptions::graph_name, "graph name written in the header comment")
      .text("input_hash", &GCodeOptions::input_hash,
            "input hash written in the header comment (default: the source file's)");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<LinkedPath>("path");
    if (path->moves.empty()) throw NodeError("the linked path has no moves");
    GCodeOptions o = ctx.options<GCodeOptions>();
    if (o.input_hash.empty() && ctx.has_input("source")) o.input_hash = ctx.input<FileRef>("source")->content_hash;
    GCode g;
    g.dialect = o.dialect;
    try {
      g.text = write_gcode(*path, o);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    ctx.set("gcode", std::move(g));
  };
  return d;
}
}  // namespace scallop::post_nodes
