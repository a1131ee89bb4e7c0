#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/cloud/clean.h"
#include "nodes/types/cloud.h"

namespace scallop::cloud_nodes {

NodeDecl make_clean_node() {
  NodeDecl d;
  d.type = "cloud.clean";
  d.version = 1;
  d.description = "drops NaN/Inf points, exact duplicates and (optionally) statistical outliers";
  d.input("cloud", "Cloud", "the raw points")
      .output("cloud", "Cloud", "the points kept, in their original order")
      .param_bool("remove_outliers", false,
                  "drop points whose mean distance to their outlier_k nearest neighbours exceeds "
                  "the global mean by outlier_std_ratio standard deviations")
      .param_int("outlier_k", 16, 2, 256, "", "neighbours used to rate a point as an outlier")
      .param_float("outlier_std_ratio", 2.0, 0.1, 100, "",
                   "outlier threshold in standard deviations above the mean distance")
      .param_int("min_points", 10, 0, 1e9, "", "fewer points than this left is an error");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    CleanOptions opts;
    opts.remove_outliers = ctx.flag("remove_outliers");
    opts.outlier_k = static_cast<int>(ctx.integer("outlier_k"));
    opts.outlier_std_ratio = ctx.number("outlier_std_ratio");
    const long long min_points = ctx.integer("min_points");

    CleanStats s;
    PointCloud out;
    try {
      out = clean_cloud(*cloud, opts, &s);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    // Points lost to NaN/Inf are a damaged file or scanner, not noise: say so on the console.
    if (s.non_finite > 0)
      ctx.warn("dropped " + std::to_string(s.non_finite) + " of " + std::to_string(s.input) +
               " points with a NaN or infinite coordinate or normal");
    const std::string counts = std::to_string(s.non_finite) + " were NaN/Inf, " +
                               std::to_string(s.duplicates) + " duplicates, " +
                               std::to_string(s.outliers) + " outliers";
    if (static_cast<long long>(s.output) < min_points)
      throw NodeError("cloud has " + std::to_string(s.output) + " points after cleaning (" +
                      counts + "); at least " + std::to_string(min_points) + " are needed");
    ctx.progress(1.0, "kept " + std::to_string(s.output) + " of " + std::to_string(s.input) +
                          " points (" + counts + ")");
    ctx.set("cloud", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
