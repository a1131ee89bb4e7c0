#include "nodes/post/refinement_seeds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace scallop {
namespace {

TEST(RefinementSeeds, TheHighestValuesSkipNaNAndNonPositive) {
  const std::vector<double> v{0.3, NAN, 0.9, 0.0, -1, 0.5, 0.7};
  auto top = highest_values(v, 2);
  std::sort(top.begin(), top.end());
  EXPECT_EQ(top, (std::vector<std::size_t>{2, 6}));
  top = highest_values(v, 10);
  std::sort(top.begin(), top.end());
  EXPECT_EQ(top, (std::vector<std::size_t>{0, 2, 5, 6}));
  EXPECT_TRUE(highest_values(v, 0).empty());
}

// 2000 samples at 1.0 in one cell fill the highest 1000; a lone 0.8 two cells away is still each
// own cell's highest, and a 0.7 (below 0.75 of the highest) is not a seed.
TEST(RefinementSeeds, ALonePeakIsNotCrowdedOut) {
  std::vector<double> v;
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 2000; ++i) v.push_back(1.0 - 1e-6 * i), p.emplace_back(0.1 + 0.0004 * i, 0.5, 0.5);
  v.push_back(0.8), p.emplace_back(2.5, 0.5, 0.5);
  v.push_back(0.79), p.emplace_back(2.6, 0.5, 0.5);  // the same cell, lower
  v.push_back(0.7), p.emplace_back(5.5, 0.5, 0.5);
  const auto top = highest_values(v, 1000);
  EXPECT_EQ(std::count(top.begin(), top.end(), std::size_t(2000)), 0);
  EXPECT_EQ(highest_per_cell(v, p, 1.0, 0.75), (std::vector<std::size_t>{0, 2000}));
  EXPECT_EQ(highest_per_cell(v, p, 1.0, 0.5), (std::vector<std::size_t>{0, 2000, 2002}));
  EXPECT_EQ(highest_per_cell(v, p, 1.0, 1.0), (std::vector<std::size_t>{0}));
}

TEST(RefinementSeeds, CellsAreCubesOfTheLatticeThroughTheOrigin) {
  // -0.1 and 0.1 lie in two cells, 0.1 and 0.9 in one; z splits cells as x and y do
  const std::vector<double> v{1, 1, 0.9, 0.95};
  const std::vector<Eigen::Vector3d> p{{-0.1, 0, 0}, {0.1, 0, 0}, {0.9, 0, 0}, {0.1, 0, 1.5}};
  EXPECT_EQ(highest_per_cell(v, p, 1.0, 0), (std::vector<std::size_t>{0, 1, 3}));
}

TEST(RefinementSeeds, NothingPositiveIsNoSeedAndBadArgumentsAreRefused) {
  const std::vector<double> none{0, NAN, -2};
  const std::vector<Eigen::Vector3d> p(3, Eigen::Vector3d::Zero());
  EXPECT_TRUE(highest_per_cell(none, p, 1.0, 0.5).empty());
  EXPECT_THROW(highest_per_cell(none, {}, 1.0, 0.5), std::invalid_argument);
  EXPECT_THROW(highest_per_cell(none, p, 0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(highest_per_cell(none, p, 1.0, 1.5), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
