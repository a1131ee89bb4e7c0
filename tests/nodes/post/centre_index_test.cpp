#include "nodes/post/centre_index.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "nodes/geom/segment.h"

namespace scallop {
namespace {

// What trace must give, by brute force over every segment: the distance to the nearest one and
// the first entry of the ray into any capsule (no candidate search, no pruning).
void brute_force(const std::vector<CentreSegment>& segs, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                 double r, double T, double delta, double& gouge, double& scallop) {
  double d = INFINITY, t = INFINITY;
  for (const auto& s : segs) {
    d = std::min(d, segment_distance(p, s.a, s.b));
    t = std::min(t, capsule_entry(p, n, s.a, s.b, r));
  }
  gouge = std::max(0.0, r - d + delta);
  if (d <= r)
    scallop = std::max(0.0, delta - (r - d));
  else
    scallop = t <= T ? t + delta : std::nan("");
}

TEST(CentreIndex, TraceEqualsTheLeastEntryOverEverySegment) {
  // Ball centres of a wavy zig-zag 4 mm above z = 0 (r = 4): passes 1.2 mm apart, 0.3 mm steps,
  // and rays from random places on and beside the surface, some inside a ball, some uncut.
  const double r = 4, T = 1.0;
  std::vector<CentreSegment> segs;
  for (int pass = 0; pass < 12; ++pass)
    for (int k = 0; k < 60; ++k) {
      auto at = [&](int j) {
        const double x = 0.3 * j, y = 1.2 * pass + 0.1 * std::sin(x);
        return Eigen::Vector3d(x, y, r + 0.2 * std::sin(0.5 * x + y));
      };
      segs.push_back({at(k), at(k + 1)});
    }
  CentreIndex index(segs, 0.5);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(-8, 26), uy(-8, 21), uz(-0.3, 0.3), tilt(-0.4, 0.4);
  std::vector<std::uint32_t> scratch;
  int uncut = 0, inside = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(tilt(rng), tilt(rng), 1).normalized();
    const double delta = trial % 3 == 0 ? 0.01 : 0.0;
    double gouge, scallop, want_gouge, want_scallop;
    index.trace(p, n, r, T, delta, gouge, scallop, scratch);
    brute_force(segs, p, n, r, T, delta, want_gouge, want_scallop);
    EXPECT_EQ(gouge, want_gouge) << trial;
    if (std::isnan(want_scallop)) {
      EXPECT_TRUE(std::isnan(scallop)) << trial;
      ++uncut;
    } else {
      EXPECT_EQ(scallop, want_scallop) << trial;
    }
    inside += want_gouge > delta;
  }
  EXPECT_GT(uncut, 100);  // the test saw rays that reach no ball ...
  EXPECT_GT(inside, 100);  // ... and places inside one
}

TEST(CentreIndex, NothingNearIsUncutAndNotGouged) {
  CentreIndex index({{{0, 0, 4}, {10, 0, 4}}}, 1.0);
  std::vector<std::uint32_t> scratch;
  double gouge = -1, scallop = -1;
  index.trace({0, 50, 0}, {0, 0, 1}, 4, 1.0, 0.0, gouge, scallop, scratch);
  EXPECT_EQ(gouge, 0);
  EXPECT_TRUE(std::isnan(scallop));
}

}  // namespace
}  // namespace scallop
