#include "nodes/cloud/cloud_height_field.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scallop {
namespace {

PointCloud bump(double height) {
  PointCloud c;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      const double x = 0.5 * i - 10, y = 0.5 * j - 10;
      c.points.push_back({x, y, height * std::exp(-(x * x + y * y) / 50)});
    }
  c.uncertainty.assign(c.points.size(), 0.01);
  return c;
}

TEST(CloudHeightField, OneModelPerCloudValueTheSameAsItsOwn) {
  const PointCloud a = bump(2), b = bump(3);
  const auto model = cloud_height_field(a);
  EXPECT_EQ(cloud_height_field(a), model);  // built once
  EXPECT_NE(cloud_height_field(b), model);
  EXPECT_EQ(&model->points(), &a.points);  // reads the cloud in place
  // the same surface and uncertainty as a model of its own (20 neighbours, the points' uncertainty)
  const HeightFieldModel own(a.points, 20, &a.uncertainty);
  double z1, z2, u1, u2;
  Eigen::Vector3d n1, n2;
  ASSERT_TRUE(model->eval(1.3, -2.1, z1, n1, false, &u1));
  ASSERT_TRUE(own.eval(1.3, -2.1, z2, n2, false, &u2));
  EXPECT_EQ(z1, z2);
  EXPECT_EQ(u1, u2);
  EXPECT_NEAR(z1, 2 * std::exp(-(1.3 * 1.3 + 2.1 * 2.1) / 50), 2e-3);
  // the 3-D tree over the same points: its nearest to a point is that point
  std::uint32_t idx;
  double d2;
  const Eigen::Vector3d q = a.points[777];
  ASSERT_EQ(model->tree3d().knnSearch(q.data(), 1, &idx, &d2), 1u);
  EXPECT_EQ(idx, 777u);
}

TEST(CloudHeightField, TooFewPointsAreRefusedEachTime) {
  PointCloud c;
  c.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(cloud_height_field(c), std::invalid_argument);
  EXPECT_THROW(cloud_height_field(c), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
