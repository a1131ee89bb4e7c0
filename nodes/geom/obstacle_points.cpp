#include "nodes/geom/obstacle_points.h"

#include <cmath>
#include <cstdint>
#include <utility>

namespace scallop {

std::vector<Eigen::Vector3d> obstacle_points(const std::vector<Eigen::Vector3d>& left_out,
                                             const HeightFieldModel& patch) {
  const double apart = 3 * patch.spacing();
  std::vector<Eigen::Vector3d> out;
  const auto& kept = patch.points();
  const auto& tree = patch.tree3d();
  for (const auto& q : left_out) {
    std::uint32_t j;
    double d2;
    if (tree.knnSearch(q.data(), 1, &j, &d2) == 0) continue;
    if (d2 <= apart * apart) continue;
    // above every kept point within twice that (on a convex rim, the patch rises beside it)
    std::vector<std::pair<std::uint32_t, double>> near;
    const double reach = 2 * apart;
    tree.radiusSearch(q.data(), reach * reach, near, nanoflann::SearchParams(32, 0, false));
    bool above = q.z() - kept[j].z() > 0.1 * std::sqrt(d2);  // the nearest, which may lie farther
    for (const auto& [i, di2] : near) above = above && q.z() - kept[i].z() > 0.1 * std::sqrt(di2);
    if (above) out.push_back(q);
  }
  return out;
}

}  // namespace scallop
