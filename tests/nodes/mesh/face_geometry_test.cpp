#include "nodes/mesh/face_geometry.h"

#include <gtest/gtest.h>

namespace scallop {
namespace {

TEST(FaceGeometry, AreaNormalCentroidOfARightTriangle) {
  Mesh m;
  m.vertices = {{1000, 0, 5}, {1002, 0, 5}, {1000, 2, 5}};  // far from the origin
  m.add_face({0, 1, 2});
  const FaceGeometry g = face_geometry(m);
  EXPECT_DOUBLE_EQ(g.area[0], 2.0);
  EXPECT_EQ(g.normal[0], Eigen::Vector3d(0, 0, 1));
  EXPECT_TRUE(g.centroid[0].isApprox(Eigen::Vector3d(1000 + 2.0 / 3, 2.0 / 3, 5)));
  EXPECT_DOUBLE_EQ(angle_deg({1, 0, 0}, {0, 1, 0}), 90.0);
  EXPECT_DOUBLE_EQ(angle_deg({1, 0, 0}, {-2, 0, 0}), 180.0);
  EXPECT_EQ(angle_deg({1, 0, 0}, {0, 0, 0}), 0.0);
}

}  // namespace
}  // namespace scallop
