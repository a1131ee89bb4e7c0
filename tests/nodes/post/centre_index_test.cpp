#include "nodes/post/centre_index.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// Ball centres of a wavy zig-zag about r above z = 0: `passes` passes `gap` apart of `steps`
// 0.3 mm steps, their height waving by `wave`; pass `lowered` 0.05 mm lower (none: -1).
std::vector<CentreSegment> wavy_zigzag(double r, int passes, int steps, double gap, double wave, int lowered) {
  std::vector<CentreSegment> segs;
  for (int pass = 0; pass < passes; ++pass)
    for (int k = 0; k < steps; ++k) {
      auto at = [&](int j) {
        const double x = 0.3 * j, y = gap * pass + 0.1 * std::sin(x);
        return Eigen::Vector3d(x, y, r + wave * std::sin(0.5 * x + y) - (pass == lowered ? 0.05 : 0.0));
      };
      segs.push_back({at(k), at(k + 1)});
    }
  return segs;
}

TEST(CentreIndex, TraceEqualsTheLeastEntryOverEverySegment) {
  // Ball centres of a wavy zig-zag 4 mm above z = 0 (r = 4): passes 1.2 mm apart, 0.3 mm steps,
  // and rays from random places on and beside the surface, some inside a ball, some uncut.
  const double r = 4, T = 1.0;
  const std::vector<CentreSegment> segs = wavy_zigzag(r, 12, 60, 1.2, 0.2, -1);
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

TEST(CentreIndex, AHintGivesTheSameAnswerAsNone) {
  // Rows of places 0.1 mm apart, as post.simulate traces them, each starting from the piece the
  // last one's answer came from; and hints that are any piece at all, or none.
  const double r = 4, T = 1.0;
  const std::vector<CentreSegment> segs = wavy_zigzag(r, 10, 50, 1.3, 0.25, 4);  // pass 4 lowered
  CentreIndex index(segs, 0.5);
  std::vector<std::uint32_t> scratch;
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> any_piece(0, 2000);
  int uncut = 0, inside = 0, rows = 0;
  for (double y = -6; y < 19; y += 0.37, ++rows) {
    std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();
    for (double x = -6; x < 21; x += 0.1) {
      const Eigen::Vector3d p(x, y, 0.2 * std::sin(0.7 * x) + (rows % 3 == 0 ? 0.3 : 0.0));
      const Eigen::Vector3d n = Eigen::Vector3d(-0.14 * std::cos(0.7 * x), 0.05, 1).normalized();
      const double delta = rows % 2 ? 0.01 : 0.0;
      double want_gouge, want_scallop;
      brute_force(segs, p, n, r, T, delta, want_gouge, want_scallop);
      std::uint32_t random_hint = any_piece(rng);
      for (std::uint32_t* h : {&hint, &random_hint}) {
        double gouge, scallop;
        index.trace(p, n, r, T, delta, gouge, scallop, scratch, h);
        EXPECT_EQ(gouge, want_gouge) << x << " " << y;
        if (std::isnan(want_scallop))
          EXPECT_TRUE(std::isnan(scallop)) << x << " " << y;
        else
          EXPECT_EQ(scallop, want_scallop) << x << " " << y;
      }
      uncut += std::isnan(want_scallop);
      inside += want_gouge > delta;
    }
  }
  EXPECT_GT(uncut, 100);
  EXPECT_GT(inside, 100);
}

TEST(CentreIndex, CandidatesKeptFromAWiderSearchGiveTheSameAnswer) {
  // The same rows, each with a cache of pieces kept from searches 0.05, 0.8 or 5 mm wider than
  // asked (a row's next places, and those of the next row, pick theirs from it): the brute
  // force's answers to the last bit.
  const double r = 4, T = 1.0;
  const std::vector<CentreSegment> segs = wavy_zigzag(r, 10, 50, 1.3, 0.25, 4);
  CentreIndex index(segs, 0.5);
  std::vector<std::uint32_t> scratch;
  for (const double slack : {0.05, 0.8, 5.0}) {
    CentreIndex::CandidateCache cache{slack};
    int rows = 0, traced = 0;
    for (double y = -6; y < 19; y += 0.37, ++rows) {
      std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();
      for (double x = -6; x < 21; x += 0.1, ++traced) {
        const Eigen::Vector3d p(x, y, 0.2 * std::sin(0.7 * x) + (rows % 3 == 0 ? 0.3 : 0.0));
        const Eigen::Vector3d n = Eigen::Vector3d(-0.14 * std::cos(0.7 * x), 0.05, 1).normalized();
        const double delta = rows % 2 ? 0.01 : 0.0;
        double want_gouge, want_scallop, gouge, scallop;
        brute_force(segs, p, n, r, T, delta, want_gouge, want_scallop);
        index.trace(p, n, r, T, delta, gouge, scallop, scratch, &hint, &cache);
        EXPECT_EQ(gouge, want_gouge) << slack << " " << x << " " << y;
        if (std::isnan(want_scallop))
          EXPECT_TRUE(std::isnan(scallop)) << slack << " " << x << " " << y;
        else
          EXPECT_EQ(scallop, want_scallop) << slack << " " << x << " " << y;
      }
    }
    EXPECT_GT(traced, 10000);
  }
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
