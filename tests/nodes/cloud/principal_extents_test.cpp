#include "nodes/cloud/principal_extents.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nodes/cloud/knn.h"

namespace scallop {
namespace {

using Eigen::Vector3d;

// n x m grid, spacing h, turned by 30 degrees in xy and tilted (extents do not follow the axes).
std::vector<Vector3d> grid(int n, int m, double h) {
  std::vector<Vector3d> P;
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double x = i * h, y = j * h;
      P.emplace_back(c * x - s * y, s * x + c * y, 0.1 * x);
    }
  return P;
}

TEST(PrincipalExtents, LengthWidthThicknessAlongTheCloudsOwnAxes) {
  const auto P = grid(101, 21, 0.5);  // 50 x 10 mm, tilted by atan(0.1) along its length
  const PrincipalExtents e = principal_extents(P);
  EXPECT_NEAR(e.length, 50 * std::sqrt(1.01), 1e-9);
  EXPECT_NEAR(e.width, 10, 1e-9);
  EXPECT_NEAR(e.thickness, 0, 1e-9);
  EXPECT_NEAR(std::abs(e.axis.dot(Vector3d(std::cos(M_PI / 6), std::sin(M_PI / 6), 0.1).normalized())), 1, 1e-12);
  EXPECT_NEAR(median_spacing(compute_knn(P, 8)), 0.5, 1e-12);
  EXPECT_EQ(one_dimensional_problem(e, 0.5), "");
}

TEST(PrincipalExtents, ALineIsOneDimensionalAStripTwoPointsWideIsNot) {
  std::vector<Vector3d> line;
  for (int i = 0; i <= 100; ++i) line.emplace_back(0.5 * i, i % 2 ? 0.003 : 0.0, 0.0);
  EXPECT_EQ(one_dimensional_problem(principal_extents(line), median_spacing(compute_knn(line, 4))),
            "the cloud is one-dimensional: its points lie along a line 50 mm long and 0.003 mm wide (points 0.5 mm "
            "apart), not on a surface; scallop machines surface patches");
  // two rows a spacing apart: a (thin) surface, refused later for what it is, if at all
  const auto strip = grid(101, 2, 0.5);
  EXPECT_EQ(one_dimensional_problem(principal_extents(strip), 0.5), "");
  // a line 2 km long on a scanner's micron grid: wider than a spacing, but under 1/1000 of its length
  PrincipalExtents e;
  e.length = 2e6, e.width = 100;
  EXPECT_NE(one_dimensional_problem(e, 0.01), "");
  // duplicates do not make the spacing 0
  std::vector<Vector3d> doubled = line;
  doubled.insert(doubled.end(), line.begin(), line.end());
  EXPECT_DOUBLE_EQ(median_spacing(compute_knn(doubled, 4)), median_spacing(compute_knn(line, 4)));
}

}  // namespace
}  // namespace scallop
