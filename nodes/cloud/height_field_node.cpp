#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/height_field.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"

namespace scallop::cloud_nodes {

NodeDecl make_height_field_node() {
  NodeDecl d;
  d.type = "cloud.height_field_check";
  d.version = 2;  // 2: a one-dimensional cloud refused; extents_mm in the report
  d.description =
      "checks that the cloud is one open height-field patch a 3-axis machine reaches from +Z "
      "(one part, no overlapping layers, no walls too steep) and passes it through";
  d.input("cloud", "Cloud", "the points with normals (oriented or not)")
      .input("neighbors", "Neighbors", "k nearest neighbours of each point (cloud.knn)")
      .output("cloud", "Cloud", "the same cloud, unchanged, once it passed")
      .output("report", "Report", "parts, points under other points, slopes, xy extent and spacing");
  using L = HeightFieldLimits;
  d.options<L>()
      .integer("min_points", &L::min_points, 0, 1e9, "", "fewer points are refused")
      .integer("max_components", &L::max_components, 1, 1e6, "",
               "separate parts (components of the neighbour graph) allowed")
      .number("min_component_fraction", &L::min_component_fraction, 0, 1, "",
              "parts with a smaller share of the points are specks: reported, ignored")
      .number("layer_gap", &L::layer_gap, 0.5, 1000, "spacings",
              "two sheets closer than this (in median point spacings) are not told apart")
      .number("max_layered_fraction", &L::max_layered_fraction, 0, 1, "",
              "share of points under other points that is tolerated (noise)")
      .number("max_slope", &L::max_slope_deg, 0, 90, "deg", "walls steeper than this are steep")
      .number("max_steep_fraction", &L::max_steep_fraction, 0, 1, "", "share of steep points that is tolerated");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    const HeightFieldLimits limits = ctx.options<HeightFieldLimits>();
    HeightFieldStats stats;
    try {
      stats = analyze_height_field(cloud->points, cloud->normals, *nbrs, limits);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    if (auto problem = height_field_problem(stats, limits); !problem.empty())
      throw NodeError(problem);
    Report report;
    report.data = to_json(stats, limits);
    ctx.set("report", std::move(report));
    ctx.set_output("cloud", cloud);  // the very same value: downstream sees it unchanged
  };
  return d;
}

}  // namespace scallop::cloud_nodes
