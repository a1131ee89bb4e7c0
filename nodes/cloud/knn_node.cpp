#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/knn.h"
#include "nodes/types/cloud.h"

namespace scallop::cloud_nodes {

NodeDecl make_knn_node() {
  NodeDecl d;
  d.type = "cloud.knn";
  d.version = 1;
  d.description = "k nearest neighbours of every point (nanoflann k-d tree, parallel)";
  d.input("cloud", "Cloud", "the points")
      .output("neighbors", "Neighbors", "k nearest neighbours of each point, nearest first")
      .param_int("k", 12, 1, 256, "", "neighbours per point, the point itself excluded");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    try {
      ctx.set("neighbors", compute_knn(cloud->points, static_cast<int>(ctx.integer("k")),
                                       [&ctx](double f) { ctx.progress(f); }));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::cloud_nodes
