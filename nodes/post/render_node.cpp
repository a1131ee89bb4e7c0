#include <stdexcept>

#include "engine/node.h"
#include "nodes/post/render.h"
#include "nodes/post/render_mesh.h"
#include "nodes/post/render_segments.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/segments.h"
#include "nodes/types/simulation.h"
#include "nodes/types/svg.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_render_node() {
  NodeDecl d;
  d.type = "post.render";
  // 2: view 'scallop' draws post.simulate's simulation instead of simulating again; 3: meshes;
  // 4: segments; 5: a whole part's scallop (mesh and simulation), view 'back'
  d.version = 6;  // 6: pictures deflated at level 1 (the same pixels)
  d.description =
      "picture of the passes over the cloud (top, iso, uv), of the scallop a simulation found (heat map), or of a "
      "mesh (shaded, feature edges red, optionally a colour per face label), PNG and SVG";
  d.input("path", "Toolpath", "the passes (views top, iso, uv)", false)
      .input("cloud", "Cloud", "the surface points, drawn shaded by height under the passes", false)
      .input("simulation", "Simulation",
             "post.simulate's simulation (view 'scallop'), or post.simulate_part's with 'mesh': the part coloured by "
             "scallop face by face, seen from two sides", false)
      .input("mesh", "Mesh", "a mesh to draw instead of passes (views iso, back, top, front)", false)
      .input("segments", "Segments",
             "a segmentation to draw instead: faces coloured by patch, sharp edges red, clipping edges dark, an "
             "arrow along each patch's machining direction (views iso, top, front)",
             false)
      .output("image", "Image", "PNG picture")
      .output("svg", "Svg", "the same as SVG")
      .param_choice("view", "top", {"top", "iso", "back", "front", "uv", "scallop"},
                    "top: xy; iso: isometric, seen from (-1, -1, 1); back: seen from (1, 1, 1) (meshes); front: "
                    "seen from -y (meshes); uv: "
                    "parameter domain; scallop: heat map of the simulation, top view, colour bar 0..1.01 h of its "
                    "limits")
      .param_int("width", 1000, 64, 8000, "px", "picture width")
      .param_bool("labels", false, "a mesh's faces coloured by their label (segments), grey where unlabelled")
      .param_bool("wireframe", false, "a mesh's polygon edges drawn thin and dark (for a few thousand faces)");
  d.run = [](NodeContext& ctx) {
    const std::string view = ctx.text("view");
    const int width = static_cast<int>(ctx.integer("width"));
    Image img;
    Svg svg;
    auto draw_mesh = [&](const Mesh& mesh, const MeshPictureOptions& o) {
      const Picture picture = render_mesh(mesh, o);
      img.png = encode_png(picture);
      svg.text = svg_of_png(picture, img.png);
    };
    try {
      if (ctx.has_input("segments")) {
        const auto segments = ctx.input<Segments>("segments");
        MeshPictureOptions o;
        o.view = view, o.width = width, o.by_label = true, o.wireframe = ctx.flag("wireframe");
        o.overlays = segment_overlays(*segments);
        draw_mesh(patch_colour_mesh(*segments), o);
      } else if (ctx.has_input("mesh") && view == "scallop") {
        if (!ctx.has_input("simulation"))
          throw NodeError("view 'scallop' of a mesh needs the input 'simulation' (post.simulate_part's)");
        const Picture picture = render_part_scallop(*ctx.input<Mesh>("mesh"), *ctx.input<Simulation>("simulation"), width);
        img.png = encode_png(picture);
        svg.text = svg_of_png(picture, img.png);
      } else if (ctx.has_input("mesh")) {
        MeshPictureOptions o;
        o.view = view, o.width = width, o.by_label = ctx.flag("labels"), o.wireframe = ctx.flag("wireframe");
        draw_mesh(*ctx.input<Mesh>("mesh"), o);
      } else if (view == "scallop") {
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
