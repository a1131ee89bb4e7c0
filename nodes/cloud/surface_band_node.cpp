#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/cloud_height_field.h"
#include "nodes/geom/surface_band.h"
#include "nodes/types/cloud.h"

namespace scallop::cloud_nodes {

NodeDecl make_surface_band_node() {
  NodeDecl d;
  d.type = "cloud.surface_band";
  d.version = 3;  // 3: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 2: the height field takes a quartic over 40 points (of z over xy, or in the tangent frame where steep) where its quadratic misfits (HeightFieldModel, kQuarticFrom)
  d.description =
      "the cloud's height field (seen from +z) sampled above every point, with how far it may be off "
      "the real surface there: the band path.gouge_guard keeps every ball out of; independent of the "
      "tool and the limits, so a run that changes them loads it from the cache";
  d.input("cloud", "Cloud", "the points (with per-point uncertainty after cloud.denoise)")
      .output("band", "Cloud",
              "one place per point: x, y, the height field's z there (the point's own z where the field "
              "does not reach), and as uncertainty its fit's (the points' uncertainty carried through "
              "it, plus 3 times its misfit)");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    try {
      // the same surface path.gouge_guard and post.simulate fit (the same model, shared)
      SurfaceBand band = surface_band(*cloud_height_field(*cloud), cloud->points);
      PointCloud out;
      out.points = std::move(band.at);
      out.uncertainty = std::move(band.uncertainty);
      ctx.set("band", std::move(out));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::cloud_nodes
