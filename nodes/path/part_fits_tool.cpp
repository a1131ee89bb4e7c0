#include "nodes/path/part_fits_tool.h"

#include <algorithm>
#include <cstdio>

namespace scallop {

std::string part_narrower_than_ball(const std::vector<Eigen::Vector3d>& P, double tool_radius) {
  if (P.empty()) return "";
  Eigen::Vector2d lo = P[0].head<2>(), hi = lo;
  for (const auto& p : P) lo = lo.cwiseMin(p.head<2>()), hi = hi.cwiseMax(p.head<2>());
  const double width = (hi - lo).maxCoeff(), ball = 2 * tool_radius;
  if (width >= ball) return "";
  // A part the ball fits were it in metres, and no wider then than a part a machine takes (10 m):
  // a room scanned in metres is 3 mm wide read as mm.
  const bool metres = width * 1000 >= ball && width <= 10;
  char buf[320];
  std::snprintf(buf, sizeof buf, "the part is %.3g mm wide, smaller than the %.3g mm ball (tool_radius %.3g mm): %s",
                width, ball, tool_radius,
                metres ? "is the cloud in metres? set the reader's scale to 1000 (--set read.scale=1000 with the "
                         "shipped graphs), or use a smaller tool"
                       : "use a smaller tool");
  return buf;
}

}  // namespace scallop
