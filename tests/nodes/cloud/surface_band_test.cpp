#include "nodes/geom/surface_band.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nodes/all_nodes.h"
#include "nodes/types/cloud.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// The plane z = 0.2 x + 0.25 y sampled every 0.25 mm over [-5, 5]^2.
std::vector<Eigen::Vector3d> plane_cloud() {
  std::vector<Eigen::Vector3d> c;
  for (double x = -5; x <= 5 + 1e-9; x += 0.25)
    for (double y = -5; y <= 5 + 1e-9; y += 0.25) c.emplace_back(x, y, 0.2 * x + 0.25 * y);
  return c;
}

TEST(SurfaceBand, OnAPlaneKnownToUIsThePlaneRaisedByU) {
  // A quadratic fits a plane exactly: no misfit, so the band's uncertainty is the points' own
  // (their mean over each fit: all 0.02), and its places lie on the plane, rim included.
  const auto cloud = plane_cloud();
  const std::vector<double> u(cloud.size(), 0.02);
  HeightFieldModel surface(cloud, 20, &u);
  const SurfaceBand band = surface_band(surface, cloud);
  ASSERT_EQ(band.at.size(), cloud.size());
  ASSERT_EQ(band.uncertainty.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_NEAR((band.at[i] - cloud[i]).norm(), 0, 1e-9) << i;
    EXPECT_NEAR(band.uncertainty[i], 0.02, 1e-12) << i;
  }
}

TEST(SurfaceBand, OnACrestItCoversTheFitsOwnError) {
  // The crest z = sqrt(1 - x^2) (radius 1 mm) for |x| <= 0.875, sampled every 0.125 mm in x and
  // 0.25 mm in y: a quadratic over 20 neighbours misses the circle. At every point the band's
  // uncertainty (3 times the fit's misfit) is at least the fit's distance from the exact crest,
  // and not zero on its top.
  std::vector<Eigen::Vector3d> cloud;
  for (double x = -0.875; x <= 0.875 + 1e-9; x += 0.125)
    for (double y = -3; y <= 3 + 1e-9; y += 0.25) cloud.emplace_back(x, y, std::sqrt(1 - x * x));
  HeightFieldModel surface(cloud, 20);
  const SurfaceBand band = surface_band(surface, cloud);
  double top = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (std::abs(cloud[i].y()) > 2) continue;  // away from the ends in y
    EXPECT_GE(band.uncertainty[i] + 1e-12, std::abs(band.at[i].z() - cloud[i].z())) << i;
    const double x = std::abs(cloud[i].x());
    if (x < 0.2) top = std::max(top, band.uncertainty[i]);
  }
  EXPECT_GT(top, 1e-3);
}

TEST(SurfaceBand, NodeGivesOnePlacePerPointWithItsUncertainty) {
  PointCloud pc;
  pc.points = plane_cloud();
  pc.uncertainty.assign(pc.points.size(), 0.01);
  auto out = test::run_node(*builtin_registry().find("cloud.surface_band"), {},
                            {{"cloud", std::make_shared<const PointCloud>(pc)}});
  auto band = std::dynamic_pointer_cast<const PointCloud>(out.at("band"));
  ASSERT_TRUE(band);
  ASSERT_EQ(band->size(), pc.size());
  ASSERT_TRUE(band->has_uncertainty());
  EXPECT_NEAR(band->uncertainty[0], 0.01, 1e-12);
  EXPECT_NEAR((band->points[17] - pc.points[17]).norm(), 0, 1e-9);

  PointCloud few;
  few.points.assign(pc.points.begin(), pc.points.begin() + 5);
  EXPECT_THROW(test::run_node(*builtin_registry().find("cloud.surface_band"), {},
                              {{"cloud", std::make_shared<const PointCloud>(few)}}),
               NodeError);
}

}  // namespace
}  // namespace scallop
