#include "nodes/path/part_fits_tool.h"

#include <gtest/gtest.h>

namespace scallop {
namespace {

std::vector<Eigen::Vector3d> square(double side) {
  std::vector<Eigen::Vector3d> P;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 4; ++j) P.emplace_back(side * i / 10, 0.5 * side * j / 4, 0.01 * side * i);
  return P;
}

TEST(PartFitsTool, APartNarrowerThanTheBallIsRefusedAndAScaleSuggestedWhenItIsMetres) {
  EXPECT_EQ(part_narrower_than_ball(square(100), 4), "");
  EXPECT_EQ(part_narrower_than_ball(square(8), 4), "");  // exactly the ball's diameter
  // a 100 mm part written in metres: exit 0 and a passing certificate, before
  EXPECT_EQ(part_narrower_than_ball(square(0.1), 4),
            "the part is 0.1 mm wide, smaller than the 8 mm ball (tool_radius 4 mm): is the cloud in metres? set "
            "the reader's scale to 1000 (--set read.scale=1000 with the shipped graphs), or use a smaller tool");
  // a Kinect scene in metres (cturtle.pcd, 2.84 m wide) was told only to use a smaller tool
  EXPECT_EQ(part_narrower_than_ball(square(2.84), 4),
            "the part is 2.84 mm wide, smaller than the 8 mm ball (tool_radius 4 mm): is the cloud in metres? set "
            "the reader's scale to 1000 (--set read.scale=1000 with the shipped graphs), or use a smaller tool");
  // in mm, only too small for this ball (20 m in metres); and too small even in metres
  EXPECT_EQ(part_narrower_than_ball(square(20), 15),
            "the part is 20 mm wide, smaller than the 30 mm ball (tool_radius 15 mm): use a smaller tool");
  EXPECT_EQ(part_narrower_than_ball(square(0.001), 4),
            "the part is 0.001 mm wide, smaller than the 8 mm ball (tool_radius 4 mm): use a smaller tool");
  EXPECT_EQ(part_narrower_than_ball({}, 4), "");
}

}  // namespace
}  // namespace scallop
