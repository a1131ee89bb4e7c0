#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/normals.h"
#include "nodes/types/cloud.h"

namespace scallop::cloud_nodes {

NodeDecl make_normals_node() {
  NodeDecl d;
  d.type = "cloud.normals";
  d.version = 1;
  d.description = "PCA normals from the k nearest neighbours, consistently oriented";
  d.input("cloud", "Cloud", "the points")
      .input("neighbors", "Neighbors", "neighbours of each point; all of its k are used")
      .output("cloud", "Cloud", "the same points with unit normals")
      .param_choice("orientation", "auto", {"up", "mst", "auto"},
                    "up: n_z >= 0 (height fields); mst: propagated over the minimum spanning "
                    "tree of the neighbour graph from the highest point, oriented +Z; auto: mst, "
                    "then all flipped if most point down");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    auto nbrs = ctx.input<Neighborhoods>("neighbors");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    PointCloud out;
    try {
      const NormalOrientation mode = parse_normal_orientation(ctx.text("orientation"));
      out.normals = estimate_normals(cloud->points, *nbrs, mode);
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    out.points = cloud->points;
    ctx.set("cloud", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
