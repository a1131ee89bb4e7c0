#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/smooth.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::cloud_nodes {

NodeDecl make_smooth_node() {
  NodeDecl d;
  d.type = "cloud.smooth";
  d.version = 1;
  d.description = "Laplacian fairing of a noisy cloud: points move along their normals only";
  d.input("cloud", "Cloud", "the points, with normals")
      .input("laplacian", "Laplacian", "the meshless Laplacian of the cloud")
      .input("loops", "Loops", "boundary flags: boundary points are kept fixed", false)
      .output("cloud", "Cloud", "the smoothed points, same normals")
      .param_int("iterations", 2, 0, 1000, "", "smoothing passes (the Laplacian is not rebuilt)")
      .param_float("lambda", 0.5, 1e-6, 1.0, "", "fraction of the normal Laplacian displacement applied per pass");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto lap = ctx.input<Laplacian>("laplacian");
    if (!cloud->has_normals()) throw NodeError("cloud.smooth needs normals: run cloud.normals first");
    std::vector<std::uint8_t> fixed;
    if (ctx.has_input("loops")) fixed = ctx.input<BoundaryLoops>("loops")->is_boundary;
    PointCloud out;
    try {
      out.points = smooth_cloud(cloud->points, cloud->normals, lap->L, fixed,
                                static_cast<int>(ctx.integer("iterations")), ctx.number("lambda"));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    out.normals = cloud->normals;
    ctx.set("cloud", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
