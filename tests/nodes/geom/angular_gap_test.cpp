#include "nodes/geom/angular_gap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace scallop {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Vector2d at(double angle, double length = 1) { return length * Eigen::Vector2d(std::cos(angle), std::sin(angle)); }

TEST(AngularGap, PseudoAngleOrdersDirectionsAsTheAngleDoes) {
  std::vector<double> angles;
  for (int j = 0; j < 720; ++j) angles.push_back(j * kPi / 360);
  for (std::size_t j = 1; j < angles.size(); ++j)
    EXPECT_LT(pseudo_angle(at(angles[j - 1]).x(), at(angles[j - 1]).y()), pseudo_angle(at(angles[j]).x(), at(angles[j]).y()))
        << angles[j];
  EXPECT_EQ(pseudo_angle(1, 0), 0);
  EXPECT_EQ(pseudo_angle(0, 2), 1);
  EXPECT_EQ(pseudo_angle(-3, 0), 2);
  EXPECT_EQ(pseudo_angle(0, -1), 3);
  EXPECT_EQ(pseudo_angle(0, 0), 0);
}

TEST(AngularGap, HalfPlaneAndRegularFan) {
  // Directions over [0, pi] (an edge point's neighbours): the gap is the other half turn.
  std::vector<Eigen::Vector2d> half;
  for (int j = 0; j <= 8; ++j) half.push_back(at(j * kPi / 8, 1 + j));
  EXPECT_NEAR(largest_angular_gap(half.data(), half.size()), kPi, 1e-14);
  // Twelve directions 30 degrees apart, shuffled, one repeated and one zero vector: 30 degrees.
  std::vector<Eigen::Vector2d> fan;
  for (int j = 0; j < 12; ++j) fan.push_back(at(0.3 + j * kPi / 6, 0.5 + 0.1 * j));
  fan.push_back(fan[4] * 3);
  fan.push_back(Eigen::Vector2d::Zero());
  std::shuffle(fan.begin(), fan.end(), std::mt19937(4));
  EXPECT_NEAR(largest_angular_gap(fan.data(), fan.size()), kPi / 6, 1e-14);
  // The widest gap straddling +x (where pseudo_angle starts again).
  std::vector<Eigen::Vector2d> straddle = {at(1), at(2), at(3), at(4.5)};
  EXPECT_NEAR(largest_angular_gap(straddle.data(), straddle.size()), 2 * kPi - 4.5 + 1, 1e-14);
}

TEST(AngularGap, FewerThanTwoDirectionsIsTheWholeTurn) {
  std::vector<Eigen::Vector2d> none = {Eigen::Vector2d::Zero()};
  EXPECT_EQ(largest_angular_gap(none.data(), 0), 2 * kPi);
  EXPECT_EQ(largest_angular_gap(none.data(), 1), 2 * kPi);
  std::vector<Eigen::Vector2d> one_way = {at(1), at(1, 3), Eigen::Vector2d::Zero(), at(1, 0.2)};
  EXPECT_EQ(largest_angular_gap(one_way.data(), one_way.size()), 2 * kPi);
  // Two directions nearly together: nearly the whole turn, whichever side of +x they lie.
  for (double base : {0.0, 1.0, kPi, -1e-3}) {
    std::vector<Eigen::Vector2d> two = {at(base), at(base + 1e-6)};
    EXPECT_NEAR(largest_angular_gap(two.data(), two.size()), 2 * kPi - 1e-6, 1e-12) << base;
  }
}

TEST(AngularGap, RoundingThatTiesNearlyEqualDirectionsIsNoFullTurn) {
  // A grid seen from a query 1e-16 off its row: the directions along the row get the same
  // pseudo_angle in either order, and their cross product says "almost a whole turn" when the
  // order is the wrong one; the widest gap is the grid's own (the measured regression: 2 pi).
  // (In this order the first version of the function gave 2 pi.)
  const double e = -2.2204460492503131e-16;
  std::vector<Eigen::Vector2d> d;
  for (double x : {0.125, -0.125, 0.375, -0.375, 0.625, -0.625}) d.emplace_back(x, e);
  for (double x : {0.125, -0.125, 0.375, -0.375})
    for (double y : {0.25 + e, -0.25 + e, 0.5 + e, -0.5 + e}) d.emplace_back(x, y);
  double expected = 0;
  std::vector<double> a;
  for (const auto& v : d) a.push_back(std::atan2(v.y(), v.x()));
  std::sort(a.begin(), a.end());
  expected = a.front() + 2 * kPi - a.back();
  for (std::size_t j = 1; j < a.size(); ++j) expected = std::max(expected, a[j] - a[j - 1]);
  EXPECT_NEAR(largest_angular_gap(d.data(), d.size()), expected, 1e-13);
  EXPECT_LT(expected, 1);
}

TEST(AngularGap, MatchesSortedAtan2OnRandomDirections) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::Vector2d> d(3 + trial % 40);
    std::vector<double> a;
    for (auto& v : d) {
      v = Eigen::Vector2d(u(rng), u(rng));
      a.push_back(std::atan2(v.y(), v.x()));
    }
    std::sort(a.begin(), a.end());
    double expected = a.front() + 2 * kPi - a.back();
    for (std::size_t j = 1; j < a.size(); ++j) expected = std::max(expected, a[j] - a[j - 1]);
    EXPECT_NEAR(largest_angular_gap(d.data(), d.size()), expected, 1e-13) << trial;
  }
}

TEST(AngularGap, EveryOctantOccupiedOnlyWhenNoGapReachesAQuarterTurn) {
  // The eight sector boundaries themselves (0, 45, ..., 315 degrees, exact on the axes and
  // diagonals) fill every sector; leave one out and its sector is empty (a gap of 90 degrees).
  std::vector<Eigen::Vector2d> corners = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
  EXPECT_TRUE(every_octant_occupied(corners.data(), corners.size()));
  for (std::size_t k = 0; k < corners.size(); ++k) {
    std::vector<Eigen::Vector2d> missing = corners;
    missing.erase(missing.begin() + std::ptrdiff_t(k));
    EXPECT_FALSE(every_octant_occupied(missing.data(), missing.size())) << k;
  }
  // Random sets: occupied means a widest gap below pi/2; and the converse fails only when some
  // gap is at least pi/4 wide (an empty sector lies inside a gap).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int occupied = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Eigen::Vector2d> d(4 + trial % 30);
    for (auto& v : d) v = Eigen::Vector2d(u(rng), u(rng));
    if (trial % 7 == 0) d.push_back(Eigen::Vector2d::Zero());
    const double gap = largest_angular_gap(d.data(), d.size());
    if (every_octant_occupied(d.data(), d.size())) {
      ++occupied;
      EXPECT_LT(gap, kPi / 2) << trial;
    } else {
      EXPECT_GE(gap, kPi / 4) << trial;
    }
  }
  EXPECT_GT(occupied, 500);  // the test saw both answers
}

TEST(AngularGap, EmptyBinRunsBoundTheWidestGap) {
  // pseudo_angle's bins start at 0, 18.43, 45, 71.57, 90 ... degrees (atan(1/3), a quarter turn's
  // bins mirrored): a direction in the middle of each fills all 16.
  constexpr double kDeg = kPi / 180;
  const double edges[5] = {0, std::atan(1.0 / 3), kPi / 4, kPi / 2 - std::atan(1.0 / 3), kPi / 2};
  std::vector<Eigen::Vector2d> mids;
  for (int q = 0; q < 4; ++q)
    for (int b = 0; b < 4; ++b) mids.push_back(at(q * kPi / 2 + 0.5 * (edges[b] + edges[b + 1])));
  EXPECT_EQ(longest_empty_bin_run(mids.data(), mids.size()), 0);
  // the upper half plane only, 0 to 179 degrees: the 8 bins below the x axis are empty
  std::vector<Eigen::Vector2d> half;
  for (int a = 0; a < 180; ++a) half.push_back(at(a * kDeg, 1 + a));
  EXPECT_EQ(longest_empty_bin_run(half.data(), half.size()), 8);
  // a run that wraps around past 360 degrees: directions from 100 to 200 degrees only
  std::vector<Eigen::Vector2d> wrap = {at(100 * kDeg), at(150 * kDeg), at(200 * kDeg)};
  EXPECT_EQ(longest_empty_bin_run(wrap.data(), wrap.size()), 10);  // bins 4, 6, 9 hold them; 10 to 3 are empty
  // no direction: all empty; zero vectors have none
  std::vector<Eigen::Vector2d> zeros(3, Eigen::Vector2d::Zero());
  EXPECT_EQ(longest_empty_bin_run(zeros.data(), 0), 16);
  EXPECT_EQ(longest_empty_bin_run(zeros.data(), zeros.size()), 16);
  zeros.push_back(at(1.0));
  EXPECT_EQ(longest_empty_bin_run(zeros.data(), zeros.size()), 15);
  // What height_field_model.cpp rests on, on random sets: fewer than 3 empty in a row, the widest
  // gap is below 106.3 degrees; 9 or more, it is at least 198.4.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int few = 0, many = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    std::vector<Eigen::Vector2d> d(2 + trial % 40);
    for (auto& v : d) v = Eigen::Vector2d(u(rng), u(rng));
    if (trial % 3 == 0)  // crowd them into a half plane or less
      for (auto& v : d) v = at(std::atan2(v.y(), v.x()) * (0.2 + 0.3 * (trial % 4)));
    const double gap = largest_angular_gap(d.data(), d.size());
    const int run = longest_empty_bin_run(d.data(), d.size());
    if (run < 3) {
      ++few;
      EXPECT_LT(gap, 106.3 * kDeg) << trial;
    }
    if (run >= 9) {
      ++many;
      EXPECT_GE(gap, 198.4 * kDeg) << trial;
    }
    if (gap > 106.4 * kDeg) EXPECT_GE(run, 3) << trial;
  }
  EXPECT_GT(few, 500);
  EXPECT_GT(many, 200);
}

TEST(AngularGap, ExceedsAgreesWithTheGapItself) {
  // The sector shortcut answers only what the widest gap would, at thresholds below, at and
  // above a quarter turn (90 degrees converted as the boundary node converts it).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<Eigen::Vector2d> d(4 + trial % 20);
    for (auto& v : d) v = Eigen::Vector2d(u(rng), u(rng));
    const double gap = largest_angular_gap(d.data(), d.size());
    for (double angle : {kPi / 3, 90 * kPi / 180, 0.6 * kPi, kPi})
      EXPECT_EQ(angular_gap_exceeds(d.data(), d.size(), angle), gap > angle) << trial << " " << angle;
  }
}

}  // namespace
}  // namespace scallop
