#include "nodes/geom/angular_gap.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace scallop {

double largest_angular_gap(const Eigen::Vector2d* d, std::size_t count) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  struct Direction {
    double key;
    Eigen::Vector2d v;
  };
  thread_local std::vector<Direction> dir;
  dir.clear();
  for (std::size_t j = 0; j < count; ++j)
    if (!d[j].isZero()) dir.push_back({pseudo_angle(d[j].x(), d[j].y()), d[j]});
  const std::size_t m = dir.size();
  if (m < 2) return kTwoPi;
  std::sort(dir.begin(), dir.end(), [](const Direction& a, const Direction& b) { return a.key < b.key; });
  // Every direction within 1e-9 of one another (in pseudo_angle, below 2e-9 rad): the gap from
  // the last round to the first is the whole turn, which the cross product's sign cannot tell.
  if (dir[m - 1].key - dir[0].key < 1e-9) return kTwoPi;
  // pseudo_angle grows at 1/2 to 1 times the angle's rate (1 / (|sin| + |cos|)^2), so a gap whose
  // pseudo_angle difference is below half the largest difference is narrower than the gap with
  // that largest difference: only the others are measured, by atan2 of their cross and dot
  // products (exact also where rounding gave nearly equal directions the same pseudo_angle).
  auto key_gap = [&](std::size_t j) { return j + 1 < m ? dir[j + 1].key - dir[j].key : 4 - dir[j].key + dir[0].key; };
  double widest_key = 0;
  for (std::size_t j = 0; j < m; ++j) widest_key = std::max(widest_key, key_gap(j));
  double widest = 0;
  for (std::size_t j = 0; j < m; ++j) {
    if (key_gap(j) < 0.5 * widest_key - 1e-12) continue;
    const Eigen::Vector2d& a = dir[j].v;
    const Eigen::Vector2d& b = dir[(j + 1) % m].v;
    const double angle = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    widest = std::max(widest, angle < 0 ? angle + kTwoPi : angle);
  }
  return widest;
}

bool every_octant_occupied(const Eigen::Vector2d* d, std::size_t count) {
  unsigned occupied = 0;
  for (std::size_t j = 0; j < count && occupied != 0xffu; ++j) {
    const double x = d[j].x(), y = d[j].y();
    // the quadrant [q pi/2, (q+1) pi/2), and (a, b) the direction turned back into the first
    // one (a > 0, b >= 0): its angle there is >= pi/4 exactly when b >= a
    int q;
    double a, b;
    if (x > 0 && y >= 0) q = 0, a = x, b = y;
    else if (x <= 0 && y > 0) q = 1, a = y, b = -x;
    else if (x < 0 && y <= 0) q = 2, a = -x, b = -y;
    else if (x >= 0 && y < 0) q = 3, a = -y, b = x;
    else continue;  // (0, 0): no direction
    occupied |= 1u << (2 * q + (b >= a ? 1 : 0));
  }
  return occupied == 0xffu;
}

int longest_empty_bin_run(const Eigen::Vector2d* d, std::size_t count) {
  unsigned occupied = 0;
  for (std::size_t j = 0; j < count && occupied != 0xffffu; ++j) {
    if (d[j].isZero()) continue;
    const int bin = std::min(15, static_cast<int>(4 * pseudo_angle(d[j].x(), d[j].y())));
    occupied |= 1u << bin;
  }
  if (occupied == 0) return 16;
  // the runs of zero bits, around the circle: start just after an occupied bin
  int start = 0;
  while (!(occupied & (1u << start))) ++start;
  int longest = 0, run = 0;
  for (int k = 1; k <= 16; ++k) {
    if (occupied & (1u << ((start + k) % 16))) run = 0;
    else longest = std::max(longest, ++run);
  }
  return longest;
}

bool angular_gap_exceeds(const Eigen::Vector2d* d, std::size_t count, double angle) {
  if (angle >= (1 - 1e-12) * std::numbers::pi / 2 && every_octant_occupied(d, count)) return false;
  if (angle >= kNoThreeEmptyBinsBelow && longest_empty_bin_run(d, count) < 3) return false;
  return largest_angular_gap(d, count) > angle;
}

}  // namespace scallop
