// The widest gap between the directions from a point to its neighbours, as boundary detection,
// the map check and the certificate's surface model use it (a point on a patch's edge sees
// its neighbours within a half-plane: a gap of at least pi).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>

namespace scallop {

// A monotone stand-in for the angle of (x, y): in [0, 4), increasing with the angle measured
// counter-clockwise from +x over [0, 2 pi); 0 for (0, 0). Orders directions as atan2 does (up to
// where the circle starts) with one division.
inline double pseudo_angle(double x, double y) {
  const double s = std::abs(x) + std::abs(y);
  if (s == 0) return 0;
  const double t = y / s;  // in [-1, 1]
  return x >= 0 ? (y >= 0 ? t : 4 + t) : 2 - t;
}

// d  `count` directions in a plane (any lengths); zero vectors have no direction and are skipped,
//    repeated directions make gaps of 0.
// Returns the largest angle (radians, in [0, 2 pi]) between circularly consecutive directions;
// 2 pi when fewer than two directions remain or all point the same way. Sorted by pseudo_angle;
// only the gaps that may be the widest are measured (atan2 of their cross and dot products).
double largest_angular_gap(const Eigen::Vector2d* d, std::size_t count);

// True when each of the eight 45-degree sectors [k pi/4, (k+1) pi/4) around the origin holds one
// of the directions d[0..count) (decided by exact comparisons): then every gap between them is
// narrower than a quarter turn, since a wider one would contain a whole sector. A cheap test
// that answers "is the widest gap over a threshold >= pi/2?" for most points inside a cloud.
bool every_octant_occupied(const Eigen::Vector2d* d, std::size_t count);

// The longest circular run of empty bins when the directions d[0..count) are sorted into 16 bins
// by pseudo_angle (a quarter of its unit each: 18.4 or 26.6 degrees wide; zero vectors skipped).
// Bounds the widest gap without sorting: a gap wider than 106.3 degrees (two of the widest bins
// beside the run) leaves at least 3 bins empty in a row, and 9 empty in a row make a gap of at
// least 198.4 degrees (5 of the narrow bins and 4 of the wide ones).
int longest_empty_bin_run(const Eigen::Vector2d* d, std::size_t count);
// Fewer than 3 empty bins in a row: the widest gap is below this (radians; 4 of the widest bins,
// 106.26 degrees, rounded up).
constexpr double kNoThreeEmptyBinsBelow = 1.8553;

// Whether largest_angular_gap(d, count) exceeds `angle`; for angle >= pi/2 (to 1e-12: 90 degrees
// converted) answered by every_octant_occupied where that holds, and for angle >=
// kNoThreeEmptyBinsBelow by longest_empty_bin_run, without sorting.
bool angular_gap_exceeds(const Eigen::Vector2d* d, std::size_t count, double angle);

}  // namespace scallop
