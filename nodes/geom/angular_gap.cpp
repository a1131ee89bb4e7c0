#include "nodes/geom/angular_gap.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace scallop {

namespace {

// Measures, by atan2 of their cross and dot products, the gaps between circularly consecutive
// directions whose pseudo_angle difference is at least half the widest such difference:
// pseudo_angle grows at 1/2 to 1 times the angle's rate (1 / (|sin| + |cos|)^2), so the others are
// narrower than the gap with that widest difference. Of the `pairs` consecutive pairs, gap(j) is
// the j-th one's pseudo_angle difference and pair(j) its two directions, in turning order.
template <class Gap, class Pair>
double widest_measured(std::size_t pairs, Gap gap, Pair pair) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  double widest_key = 0;
  for (std::size_t j = 0; j < pairs; ++j) widest_key = std::max(widest_key, gap(j));
  double widest = 0;
  for (std::size_t j = 0; j < pairs; ++j) {
    if (gap(j) < 0.5 * widest_key - 1e-12) continue;
    const auto [a, b] = pair(j);
    const double angle = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    widest = std::max(widest, angle < 0 ? angle + kTwoPi : angle);
  }
  return widest;
}

}  // namespace

double largest_angular_gap(const Eigen::Vector2d* d, std::size_t count) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  // First without sorting: the directions in 64 buckets of pseudo_angle (a 16th of its unit
  // each), each bucket's first and last. Where two consecutive non-empty buckets leave a gap of
  // two buckets' width or more, no gap inside a bucket (less than one wide) is half the widest,
  // and the gaps between buckets are all that widest_measured looks at: the same answer as
  // sorting them all, in one pass (where the widest gap is narrower, they are sorted).
  constexpr int kBuckets = 64;
  struct Bucket {
    double lo = INFINITY, hi = -INFINITY;
    const Eigen::Vector2d* lo_at = nullptr;
    const Eigen::Vector2d* hi_at = nullptr;
  };
  Bucket bucket[kBuckets];
  std::size_t m = 0;
  for (std::size_t j = 0; j < count; ++j) {
    if (d[j].isZero()) continue;
    const double key = pseudo_angle(d[j].x(), d[j].y());
    Bucket& b = bucket[std::min(kBuckets - 1, static_cast<int>(kBuckets / 4 * key))];
    if (key < b.lo) b.lo = key, b.lo_at = &d[j];
    if (key > b.hi) b.hi = key, b.hi_at = &d[j];
    ++m;
  }
  if (m < 2) return kTwoPi;
  int used[kBuckets], n_used = 0;
  for (int k = 0; k < kBuckets; ++k)
    if (bucket[k].lo_at) used[n_used++] = k;
  // Every direction within 1e-9 of one another (in pseudo_angle, below 2e-9 rad): the gap from
  // the last round to the first is the whole turn, which the cross product's sign cannot tell.
  if (bucket[used[n_used - 1]].hi - bucket[used[0]].lo < 1e-9) return kTwoPi;
  auto bucket_gap = [&](std::size_t j) {
    const Bucket &a = bucket[used[j]], &b = bucket[used[(j + 1) % n_used]];
    return j + 1 < std::size_t(n_used) ? b.lo - a.hi : 4 - a.hi + b.lo;
  };
  double widest_between = 0;
  for (int j = 0; j < n_used; ++j) widest_between = std::max(widest_between, bucket_gap(j));
  if (n_used > 1 && widest_between >= 2.0 / (kBuckets / 4) + 4e-12)
    return widest_measured(n_used, bucket_gap, [&](std::size_t j) {
      return std::pair<const Eigen::Vector2d&, const Eigen::Vector2d&>(*bucket[used[j]].hi_at,
                                                                       *bucket[used[(j + 1) % n_used]].lo_at);
    });
  struct Direction {
    double key;
    Eigen::Vector2d v;
  };
  thread_local std::vector<Direction> dir;
  dir.clear();
  for (std::size_t j = 0; j < count; ++j)
    if (!d[j].isZero()) dir.push_back({pseudo_angle(d[j].x(), d[j].y()), d[j]});
  std::sort(dir.begin(), dir.end(), [](const Direction& a, const Direction& b) { return a.key < b.key; });
  return widest_measured(
      m, [&](std::size_t j) { return j + 1 < m ? dir[j + 1].key - dir[j].key : 4 - dir[j].key + dir[0].key; },
      [&](std::size_t j) {
        return std::pair<const Eigen::Vector2d&, const Eigen::Vector2d&>(dir[j].v, dir[(j + 1) % m].v);
      });
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
