// A point as messages print it: "(x, y, z)" with `decimals` digits after the point.
#pragma once

#include <Eigen/Core>
#include <cstdio>
#include <string>

namespace scallop {

inline std::string point_text(const Eigen::Vector3d& p, int decimals) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.*f, %.*f, %.*f)", decimals, p.x(), decimals, p.y(), decimals, p.z());
  return buf;
}

}  // namespace scallop
