#include <stdexcept>

#include "engine/node.h"
#include "nodes/post/render.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/simulation.h"
#include "nodes/types/svg.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_render_node() {
  NodeDecl d;
  d.type = "post.render";
  d.version = 2;  // 2: view 'scallop' draws post.simulate's simulation instead of simulating again
  d.description =
      "picture of the passes over the cloud (top, iso, uv) or of the scallop a simulation found (heat map), PNG and SVG";
  d.input("path", "Toolpath", "the passes (views top, iso, uv)", false)
      .input("cloud", "Cloud", "the surface points, drawn shaded by height under the passes", false)
      .input("simulation", "Simulation", "post.simulate's simulation (view 'scallop')", false)
      .output("image", "Image", "PNG picture")
      .output("svg", "Svg", "the same as SVG")
      .param_choice("view", "top", {"top", "iso", "uv", "scallop"},
                    "top: xy; iso: isometric; uv: parameter domain; scallop: heat map of the simulation, "
                    "top view, colour bar 0..1.01 h of its limits")
      .param_int("width", 1000, 64, 8000, "px", "picture width");
  d.run = [](NodeContext& ctx) {
    const std::string view = ctx.text("view");
    const int width = static_cast<int>(ctx.integer("width"));
    Image img;
    Svg svg;
    try {
      if (view == "scallop") {
        if (!ctx.has_input("simulation")) throw NodeError("view 'scallop' needs the input 'simulation' (post.simulate's)");
        auto sim = ctx.input<Simulation>("simulation");
        img.png = render_scallop_png(*sim, width);
        svg.text = render_scallop_svg(*sim, width);
      } else {
        if (!ctx.has_input("path")) throw NodeError("view '" + view + "' needs the input 'path'");
        auto path = ctx.input<Toolpath>("path");
        std::shared_ptr<const PointCloud> cloud;
        if (ctx.has_input("cloud")) cloud = ctx.input<PointCloud>("cloud");
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
