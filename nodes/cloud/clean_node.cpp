#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/cloud/clean.h"
#include "nodes/types/cloud.h"

namespace scallop::cloud_nodes {

NodeDecl make_clean_node() {
  NodeDecl d;
  d.type = "cloud.clean";
  d.version = 3;  // 3: remove_stray (stop 90)
  d.description = "drops NaN/Inf points, exact duplicates and (optionally) statistical outliers and stray points off the surface";
  d.input("cloud", "Cloud", "the raw points")
      .output("cloud", "Cloud", "the points kept, along a space-filling curve (or in their original order)");
  d.options<CleanOptions>()
      .flag("remove_outliers", &CleanOptions::remove_outliers,
            "drop points whose mean distance to their outlier_k nearest neighbours exceeds "
            "the global mean by outlier_std_ratio standard deviations")
      .integer("outlier_k", &CleanOptions::outlier_k, 2, 256, "", "neighbours used to rate a point as an outlier")
      .number("outlier_std_ratio", &CleanOptions::outlier_std_ratio, 0.1, 100, "",
              "outlier threshold in standard deviations above the mean distance")
      .flag("remove_stray", &CleanOptions::remove_stray,
            "drop stray points: those farther from the quadric their stray_k nearest sample than 8 times "
            "its rms residual (at least the cloud's median) and a twentieth of their k-th distance, or "
            "isolated (a scanner's spikes, flying pixels, reflections: a point under the surface makes the "
            "cloud look layered, one above it is a spike the guard lifts every ball over)")
      .integer("stray_k", &CleanOptions::stray_k, 8, 256, "", "neighbours whose quadric judges a point as stray")
      .flag("spatial_order", &CleanOptions::spatial_order,
            "put the points along a space-filling curve (Morton order), so that neighbours are near one "
            "another in memory: every later node reads them faster (a million points in random order: "
            "the harmonic solve 2 to 3 times slower); false keeps the input's order");
  d.param_int("min_points", 10, 0, 1e9, "", "fewer points than this left is an error");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    const CleanOptions opts = ctx.options<CleanOptions>();
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
    if (s.stray > 0)
      ctx.warn("dropped " + std::to_string(s.stray) + " of " + std::to_string(s.input) +
               " points lying off the surface their neighbours sample (stray points)");
    const std::string counts = std::to_string(s.non_finite) + " were NaN/Inf, " +
                               std::to_string(s.duplicates) + " duplicates, " +
                               std::to_string(s.outliers) + " outliers, " + std::to_string(s.stray) + " stray";
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
