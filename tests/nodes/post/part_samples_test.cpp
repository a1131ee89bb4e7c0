#include "nodes/post/part_samples.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scallop {
namespace {

using V = Eigen::Vector3d;

Mesh triangle(const V& a, const V& b, const V& c) {
  Mesh m;
  m.vertices = {a, b, c};
  m.add_face_range(std::array<std::uint32_t, 3>{0, 1, 2});
  return m;
}

TEST(PartSamples, WeightsAddUpToTheAreaAndPointsFollowIt) {
  // A right triangle of legs 10 and 6: area 30.
  const auto tris = part_triangles(triangle(V(0, 0, 0), V(10, 0, 0), V(0, 6, 0)));
  ASSERT_EQ(tris.size(), 1u);
  const auto samples = sample_part(tris, 0.1);
  double area = 0;
  for (const auto& s : samples) {
    area += s.weight;
    EXPECT_TRUE(in_part_triangle(tris[0], s.p));
    EXPECT_EQ(s.tri, 0u);
  }
  EXPECT_NEAR(area, 30, 1e-9);
  EXPECT_EQ(samples.size(), part_sample_count(tris, 0.1));
  // Strips over the hypotenuse (height 60 / sqrt(136)), k of them; their mid-widths over the
  // spacing add up to area / (spacing x strip height), and each strip's ceiling adds under one.
  const double height = 60 / std::sqrt(136.0);
  const int k = int(std::ceil(height / 0.1));
  const double points = 30 / (0.1 * height / k);
  EXPECT_GE(double(samples.size()), points);
  EXPECT_LE(double(samples.size()), points + k);
}

TEST(PartSamples, ASliverGetsARowNotASquare) {
  // 10 mm long, 0.01 mm high: one strip, its mid-line 5 mm long, 50 points at spacing 0.1 (n²
  // centroids gave 4489).
  const auto tris = part_triangles(triangle(V(0, 0, 0), V(10, 0, 0), V(5, 0.01, 0)));
  const auto samples = sample_part(tris, 0.1);
  EXPECT_EQ(samples.size(), 50u);  // the strip's mid-line is half the base long
  double area = 0;
  for (const auto& s : samples) area += s.weight;
  EXPECT_NEAR(area, 0.05, 1e-12);
}

TEST(PartSamples, TheSpacingIsRaisedToTheBudget) {
  const auto tris = part_triangles(triangle(V(0, 0, 0), V(10, 0, 0), V(0, 6, 0)));
  const double s = part_sample_spacing(tris, 0.01, 1000);
  EXPECT_LE(part_sample_count(tris, s), 1000u);
  EXPECT_GT(part_sample_count(tris, s / 1.15), 1000u);
}

}  // namespace
}  // namespace scallop
