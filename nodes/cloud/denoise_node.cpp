#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/denoise.h"
#include "nodes/types/cloud.h"

namespace scallop {

NodeDecl make_denoise_node() {
  NodeDecl d;
  d.type = "cloud.denoise";
  d.version = 1;
  d.description =
      "moving-least-squares denoising: each point projected along its local normal onto a "
      "weighted quadric fitted to its neighbours (parallel)";
  d.input("cloud", "Cloud", "the noisy points; their normals, if any, only orient the new ones")
      .input("neighbors", "Neighbors",
             "neighbours of each point (its first k are used); computed here when absent", false)
      .output("cloud", "Cloud", "the projected points, with normals from the fitted quadrics")
      .param_int("k", 64, 6, 512, "",
                 "neighbours in each fit; more averages more noise away (noise in the normal "
                 "direction falls roughly as 1/sqrt(k)) but smooths more of the shape")
      .param_float("radius", 0.0, 0.0, 1e6, "mm",
                   "0: each fit uses its k neighbours, Gaussian weights of width half the "
                   "distance to the k-th; > 0: only neighbours within radius, width radius/2")
      .param_int("iterations", 1, 0, 20, "", "projections in sequence")
      .param_bool("normals", true,
                  "set normals from the fitted quadrics (oriented like the input normals, or "
                  "+Z); otherwise the input normals are kept");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    std::shared_ptr<const Neighborhoods> nbrs;
    if (ctx.has_input("neighbors")) nbrs = ctx.input<Neighborhoods>("neighbors");
    DenoiseOptions o;
    o.k = static_cast<int>(ctx.integer("k"));
    o.radius = ctx.number("radius");
    o.iterations = static_cast<int>(ctx.integer("iterations"));
    o.set_normals = ctx.flag("normals");
    static const std::vector<Eigen::Vector3d> none;
    const auto& N = cloud->has_normals() ? cloud->normals : none;
    DenoiseResult r;
    try {
      r = mls_denoise(cloud->points, N, o, nbrs.get(),
                      [&](double f) { ctx.progress(f, "denoising"); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    PointCloud out;
    out.points = std::move(r.points);
    out.normals = o.set_normals ? std::move(r.normals) : cloud->normals;
    ctx.set("cloud", std::move(out));
  };
  return d;
}

}  // namespace scallop
