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
      .output("gcode", "GCode", "the program text")
      .param_choice("dialect", "linuxcnc", {"linuxcnc", "grbl", "fanuc"},
                    "controller dialect: linuxcnc (M2), grbl (M2), fanuc (% framing, O-number, M30)")
      .param_float("feed", 1000, 1e-3, 1e6, "mm/min", "feed rate of cutting moves")
      .param_float("plunge_feed", 300, 1e-3, 1e6, "mm/min", "feed rate of plunges")
      .param_float("spindle_rpm", 10000, 0, 1e6, "rpm", "spindle speed (M3 S..); 0 writes no spindle words")
      .param_bool("arcs", false, "replace runs of feed points lying on a circle (XY, XZ or YZ plane) by G2/G3")
      .param_float("arc_tolerance", 0, 0, 1, "mm",
                   "largest distance between an arc and the points it replaces; 0: the chord error of the path (at least 0.001)")
      .param_int("program_number", 1000, 1, 9999, "", "fanuc O-number")
      .param_string("graph_name", "", "graph name written in the header comment")
      .param_string("input_hash", "", "input hash written in the header comment (default: the source file's)");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<LinkedPath>("path");
    if (path->moves.empty()) throw NodeError("the linked path has no moves");
    GCodeOptions o;
    o.dialect = ctx.text("dialect");
    o.feed = ctx.number("feed");
    o.plunge_feed = ctx.number("plunge_feed");
    o.spindle_rpm = ctx.number("spindle_rpm");
    o.arcs = ctx.flag("arcs");
    o.arc_tolerance = ctx.number("arc_tolerance");
    o.program_number = static_cast<int>(ctx.integer("program_number"));
    o.graph_name = ctx.text("graph_name");
    o.input_hash = ctx.text("input_hash");
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
