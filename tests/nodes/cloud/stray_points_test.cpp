#include "nodes/cloud/stray_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "nodes/cloud/clean.h"
#include "nodes/cloud/knn.h"

namespace scallop {
namespace {

// A wavy 40 x 30 patch with a rounded crest of radius 1 mm across it (flanks of slope 0.7),
// `n` points uniform over it, Gaussian noise sigma on z.
double surface_z(double x, double y) {
  return 2 * std::sin(x / 7) * std::cos(y / 5) - 0.7 * std::hypot(x - 20, 0.7);
}
std::vector<Eigen::Vector3d> patch(int n, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0, 40), uy(0, 30);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  std::vector<Eigen::Vector3d> P;
  for (int i = 0; i < n; ++i) {
    const double x = ux(rng), y = uy(rng);
    P.emplace_back(x, y, surface_z(x, y) + (sigma > 0 ? noise(rng) : 0));
  }
  return P;
}

// Stray points added to a patch: 0.3 to 3 mm above and below it (on the crest too; on a clean
// patch 0.1 mm too), and 12 in
// the air 3 to 8 mm above it, some of them each other's nearest. (A burst of points all within a
// millimetre of one another samples a surface of its own and stays.)
struct Strays {
  std::vector<Eigen::Vector3d> P;
  std::size_t first_stray = 0;
};
Strays with_strays(std::vector<Eigen::Vector3d> P, bool clean) {
  Strays s;
  s.first_stray = P.size();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> ux(2, 38), uy(2, 28), off(0.3, 3), unit(0, 1);
  for (int i = 0; i < 40; ++i) {
    const double x = i < 8 ? 20 + 0.1 * (i - 4) : ux(rng), y = uy(rng);
    s.P.emplace_back();
    P.emplace_back(x, y, surface_z(x, y) + (i % 2 ? 1 : -1) * off(rng));
  }
  // on a clean cloud, 0.1 mm off is stray too
  for (int i = 0; clean && i < 6; ++i) {
    const double x = ux(rng), y = uy(rng);
    P.emplace_back(x, y, surface_z(x, y) + (i % 2 ? 0.1 : -0.1));
  }
  for (int i = 0; i < 12; ++i) {
    const double x = i % 2 ? 10 + unit(rng) : ux(rng), y = i % 2 ? 10 + 2 * unit(rng) : uy(rng);
    P.emplace_back(x, y, surface_z(x, y) + 3 + 5 * unit(rng));
  }
  s.P = std::move(P);
  return s;
}

void expect_exactly_the_strays(const Strays& s, double sigma) {
  SCOPED_TRACE("noise " + std::to_string(sigma));
  // (points in the air that are each other's nearest go in cloud.clean's later rounds)
  CleanOptions o;
  o.remove_stray = true;
  o.spatial_order = false;
  PointCloud in;
  in.points = s.P;
  CleanStats stats;
  const PointCloud out = clean_cloud(in, o, &stats);
  EXPECT_EQ(stats.stray, s.P.size() - s.first_stray);
  ASSERT_EQ(out.size(), s.first_stray);
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out.points[i], s.P[i]) << i;
}

TEST(StrayPoints, SpikesPitsAndABurstInTheAirGoTheCrestAndTheNoiseStay) {
  for (double sigma : {0.0, 0.02}) expect_exactly_the_strays(with_strays(patch(12000, sigma, 3), sigma == 0), sigma);
}

// Without stray points nothing is flagged, and every point's distance from its neighbours' quadric
// is its noise: under 8 of their rms residuals or a fifth of the k-th neighbour's distance.
TEST(StrayPoints, NoneOnACleanOrNoisyPatchWithACrest) {
  for (double sigma : {0.0, 0.02}) {
    const auto P = patch(12000, sigma, 4);
    std::vector<double> off;
    const auto flags = stray_points(P, compute_knn(P, 16), &off);
    std::size_t flagged = 0;
    for (auto f : flags) flagged += f;
    EXPECT_EQ(flagged, 0u) << "noise " << sigma;
    double worst = 0;
    for (double d : off) worst = std::max(worst, d);
    EXPECT_LT(worst, sigma > 0 ? 10 * sigma : 0.05) << "noise " << sigma;
  }
}

TEST(StrayPoints, BadInput) {
  const auto P = patch(100, 0, 1);
  EXPECT_THROW(stray_points(P, compute_knn(P, 6)), std::invalid_argument);
  std::vector<Eigen::Vector3d> fewer(P.begin(), P.begin() + 50);
  EXPECT_THROW(stray_points(fewer, compute_knn(P, 16)), std::invalid_argument);
  CleanOptions o;
  o.remove_stray = true;
  o.stray_k = 4;
  PointCloud in;
  in.points = P;
  try {
    clean_cloud(in, o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "stray point removal needs stray_k >= 8 (got 4)");
  }
}

}  // namespace
}  // namespace scallop
