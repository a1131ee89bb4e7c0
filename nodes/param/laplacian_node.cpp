#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/laplacian.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::param_nodes {

NodeDecl make_laplacian_node() {
  NodeDecl d;
  d.type = "param.laplacian";
  d.version = 3;  // 2: optimal weights through the 2 x 2 form (the same weights, other rounding); 3: keeps its t and regularization (param.harmonic rebuilds rows with them)
  // Cheaper to build again (1.2 s at a million points) than to write and read its #P (k + 1)
  // entries (200 MB, 7 s of a cold run's disk cache at a million points); only param.harmonic,
  // whose own map is cached, reads it.
  d.cache_on_disk = false;
  d.description = "meshless Laplacian on the KNN graph (uniform, heat kernel or optimal weights)";
  d.input("cloud", "Cloud", "the points (normals give the tangent planes of the optimal scheme)")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point")
      .output("laplacian", "Laplacian", "row i: (L f)_i = f_i - sum_j w_ij f_j, sum_j w_ij = 1")
      .param_choice("scheme", "optimal", {"uniform", "heat", "optimal"},
                    "uniform: w = 1; heat: w = exp(-d^2/t) (Belkin); optimal: Schmidt & Singh")
      .param_float("t", 0.0, 0.0, 1e12, "mm^2", "heat-kernel time; 0: the mean squared neighbour distance")
      .param_float("regularization", 1e-3, 1e-12, 1.0, "",
                   "optimal scheme: delta in (C + delta trace(C) I) w = 1");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    Laplacian out;
    try {
      LaplacianScheme s = parse_laplacian_scheme(ctx.text("scheme"));
      out.scheme = to_string(s);
      out.heat_time = s == LaplacianScheme::Heat ? heat_time(*nbrs, ctx.number("t")) : 0.0;
      out.regularization = ctx.number("regularization");
      out.L = build_laplacian(cloud->points, cloud->has_normals() ? cloud->normals : std::vector<Eigen::Vector3d>{},
                              *nbrs, s, out.heat_time, out.regularization, [&ctx](double f) { ctx.progress(f); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    ctx.set("laplacian", std::move(out));
  };
  return d;
}

}  // namespace scallop::param_nodes
