// Numbers and points as messages print them.
#pragma once

#include <Eigen/Core>
#include <cstdio>
#include <string>

namespace scallop {

// v with `significant` digits (printf's %g: 0.0521, 1.285e-05).
inline std::string short_number(double v, int significant = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", significant, v);
  return buf;
}

// "(x, y, z)" with `decimals` digits after the point.
inline std::string point_text(const Eigen::Vector3d& p, int decimals) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.*f, %.*f, %.*f)", decimals, p.x(), decimals, p.y(), decimals, p.z());
  return buf;
}

}  // namespace scallop
