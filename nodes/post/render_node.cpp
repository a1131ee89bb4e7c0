#include <stdexcept>

#include "engine/node.h"
#include "nodes/post/render.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/svg.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_render_node() {
  NodeDecl d;
  d.type = "post.render";
  d.version = 1;
  d.description = "picture of the passes over the cloud (top, iso, uv) or of the scallop left (heat map), PNG and SVG";
  d.input("path", "Toolpath", "the passes")
      .input("cloud", "Cloud", "the surface points, drawn shaded by height (required for view 'scallop')", false)
      .output("image", "Image", "PNG picture")
      .output("svg", "Svg", "the same as SVG")
      .param_choice("view", "top", {"top", "iso", "uv", "scallop"},
                    "top: xy; iso: isometric; uv: parameter domain; scallop: heat map (runs the simulation of post.simulate)")
      .param_int("width", 1000, 64, 8000, "px", "picture width")
      .param_float("scallop", 0, 0, 100, "mm", "view scallop: limit h; 0: the path's own")
      .param_float("chord", -1, -1, 100, "mm", "view scallop: chord tolerance; -1: the path's own");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<Toolpath>("path");
    std::string view = ctx.text("view");
    int width = static_cast<int>(ctx.integer("width"));
    std::shared_ptr<const PointCloud> cloud;
    if (ctx.has_input("cloud")) cloud = ctx.input<PointCloud>("cloud");
    Image img;
    Svg svg;
    try {
      if (view == "scallop") {
        if (!cloud) throw NodeError("view 'scallop' needs the input 'cloud'");
        SimulateOptions o;
        o.tool_radius = path->tool_radius;
        o.scallop = ctx.number("scallop") > 0 ? ctx.number("scallop") : path->scallop_height;
        o.chord = ctx.number("chord") >= 0 ? ctx.number("chord") : path->chord_error;
        HeightFieldModel surf(cloud->points);
        auto sim = simulate_cut(surf, feed_centres(*path), 0, o, [&](double f) { ctx.progress(f, "simulating"); });
        double gt = std::max(o.chord, 1e-3);
        img.png = render_scallop_png(sim, o.scallop, gt, width);
        svg.text = render_scallop_svg(sim, o.scallop, gt, width);
      } else {
        img.png = encode_png(render_path(*path, cloud.get(), view, width));
        svg.text = render_path_svg(*path, cloud.get(), view, width);
      }
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    ctx.set("image", std::move(img));
    ctx.set("svg", std::move(svg));
  };
  return d;
}
}  // namespace scallop::post_nodes
