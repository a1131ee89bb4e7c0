#include "engine/node.h"
#include "nodes/cloud/cloud_height_field.h"
#include "nodes/post/surface_grid.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::post_nodes {
NodeDecl make_surface_samples_node() {
  NodeDecl d;
  d.type = "post.surface_samples";
  d.version = 3;  // 3: the rim band reaches into the holes too (stop 90); 2: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88)
  d.description =
      "the cloud's surface sampled where the certificate measures (post.simulate's grid), taken while the path is "
      "planned";
  d.input("cloud", "Cloud", "the surface, seen from +z (post.simulate's cloud)")
      .input("loops", "Loops", "the patch's boundary loops (post.simulate's); absent: the outline is guessed from the cloud",
             false)
      .output("samples", "SurfaceSamples",
              "place, normal, area and uncertainty of every sample, for post.simulate's input 'samples'");
  d.options<SurfaceGridOptions>()
      .number("tool_radius", &SurfaceGridOptions::tool_radius, 0, 1000, "mm", "r, the path's (the grid's spacing is sqrt(8 r h) / 12)")
      .number("scallop_height", &SurfaceGridOptions::scallop, 0, 100, "mm", "h, the limit post.simulate judges against")
      .number("spacing", &SurfaceGridOptions::spacing, 0, 100, "mm", "grid spacing; 0: sqrt(8 r h)/12 (post.simulate's)")
      .number("rim_band", &SurfaceGridOptions::rim_band, -1, 100, "mm", "post.simulate's rim_band")
      .integer("max_samples", &SurfaceGridOptions::max_samples, 1000, 100000000, "",
               "the spacing is raised to stay below this many samples (post.simulate's)");
  // At a million points 100 MB, retaken faster than written and read back, and the limits they
  // depend on are what a rerun changes.
  d.cache_on_disk = false;
  d.run = [](NodeContext& ctx) {
    SurfaceGridOptions o = ctx.options<SurfaceGridOptions>();
    if (!(o.tool_radius > 0) || !(o.scallop > 0))
      throw NodeError("tool_radius and scallop_height must be given (> 0): the path's, which post.simulate judges against");
    auto cloud = ctx.input<PointCloud>("cloud");
    try {
      if (ctx.has_input("loops")) o.loops = loop_polygons_xy(*ctx.input<BoundaryLoops>("loops"), cloud->points);
      ctx.set("samples", sample_surface_grid(*cloud_height_field(*cloud), o,
                                             [&](double f) { ctx.progress(f, "sampling the surface"); }));
    } catch (const std::invalid_argument& ex) {
      throw NodeError(ex.what());
    }
  };
  return d;
}
}  // namespace scallop::post_nodes
