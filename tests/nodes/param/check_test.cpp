#include "nodes/param/check.h"

#include <gtest/gtest.h>

#include <random>

#include "engine/node.h"
#include "nodes/types/param.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace param_nodes {
NodeDecl make_map_check_node();
}
namespace {

TEST(MapCheck, IdentityIsConformalAndUnfolded) {
  PointCloud c = test::random_disk(1000, 10, 31);
  auto nb = compute_knn(c.points, 12);
  std::vector<Eigen::Vector2d> uv;
  for (const auto& p : c.points) uv.push_back(3 * p.head<2>());
  MapCheck m = check_map(c.points, c.normals, nb, uv);
  EXPECT_EQ(m.foldovers, 0u);
  EXPECT_EQ(m.first_foldover, -1);
  EXPECT_NEAR(m.report["conformality"]["max"].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(m.report["conformality"]["histogram"]["counts"][0].get<int>(), 1000);
  EXPECT_TRUE(m.report["first_foldover"].is_null());
}

TEST(MapCheck, StretchIsMeasured) {
  PointCloud c = test::random_disk(500, 10, 32);
  auto nb = compute_knn(c.points, 12);
  std::vector<Eigen::Vector2d> uv;
  for (const auto& p : c.points) uv.emplace_back(2 * p.x(), p.y());
  MapCheck m = check_map(c.points, c.normals, nb, uv);
  EXPECT_NEAR(m.report["conformality"]["p50"].get<double>(), 2.0, 1e-9);
  EXPECT_EQ(m.foldovers, 0u);
}

TEST(MapCheck, MirrorFoldsEverywhere) {
  PointCloud c = test::random_disk(400, 10, 33);
  auto nb = compute_knn(c.points, 12);
  std::vector<Eigen::Vector2d> uv;
  for (const auto& p : c.points) uv.emplace_back(p.x(), -p.y());
  MapCheck m = check_map(c.points, c.normals, nb, uv);
  EXPECT_EQ(m.foldovers, 400u);
  EXPECT_EQ(m.first_foldover, 0);
  char want[256];
  std::snprintf(want, sizeof want, "the (u,v) map folds over at 400 points (first near %.3f, %.3f, %.3f): ",
                c.points[0].x(), c.points[0].y(), c.points[0].z());
  EXPECT_EQ(foldover_message(m, c.points).rfind(want, 0), 0u) << foldover_message(m, c.points);
  // only advice that was seen to help (stop 74, the camelhead scan x500: heat 99 -> 3 fold-overs,
  // uniform 4, k = 24 or 32 520 and 919, max_slope 70 568, more untangle_rounds alone 99)
  EXPECT_NE(foldover_message(m, c.points).find("param.laplacian's heat scheme left the fewest"), std::string::npos);
  // and the raster, whose map cannot fold (stop 94: the bunny scan at max_slope 75, 10 fold-overs
  // with the harmonic map, none with the planar one)
  EXPECT_NE(foldover_message(m, c.points).find("graphs/raster-zigzag.json maps the patch by its own xy"),
            std::string::npos);
  EXPECT_EQ(foldover_message(m, c.points).find("a larger k"), std::string::npos);
}

// Allowed, fold-overs are said on the terminal: on a planar map (param.planar, the points' own
// xy) as an overhang of the cloud, on a harmonic one as paths that may cross.
TEST(MapCheckNode, FoldOversAllowedAreSaidInAWarning) {
  const NodeDecl d = param_nodes::make_map_check_node();
  auto cloud = std::make_shared<PointCloud>(test::random_disk(400, 10, 33));
  auto nb = std::make_shared<Neighborhoods>(compute_knn(cloud->points, 12));
  for (const char* domain : {"planar", "disk"}) {
    auto map = std::make_shared<UVMap>();
    map->domain = domain;
    map->radius = map->width = map->height = 20;
    for (const auto& p : cloud->points) map->uv.emplace_back(p.x(), -p.y());  // mirrored: folded everywhere
    std::vector<std::string> warnings;
    NodeContext ctx(d, "check", "part", {{"untangle_rounds", 0}, {"allow_foldovers", true}},
                    {{"map", map}, {"cloud", cloud}, {"neighbors", nb}}, nullptr,
                    [&](const std::string& m) { warnings.push_back(m); });
    d.run(ctx);
    ASSERT_EQ(warnings.size(), 1u) << domain;
    const std::string head = std::string(domain) == "planar" ? "the cloud overhangs at 400 points (first near "
                                                             : "the (u,v) map folds over at 400 points (first near ";
    EXPECT_EQ(warnings[0].rfind(head, 0), 0u) << warnings[0];
  }
}

TEST(MapCheck, NonUniformDensityHasNoFoldovers) {
  // Density ramps 5:1 from x = 0 to x = 30 on a 30 x 20 patch (rejection sampling).
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> ux(0, 30), uy(0, 20), acc(0, 1);
  PointCloud c;
  while (c.points.size() < 3000) {
    double x = ux(rng), y = uy(rng);
    if (acc(rng) <= (1 + 4 * (30 - x) / 30) / 5) c.points.emplace_back(x, y, 0.3 * std::sin(x / 5));
  }
  for (const auto& p : c.points) c.normals.push_back(Eigen::Vector3d(-0.3 / 5 * std::cos(p.x() / 5), 0, 1).normalized());
  // k = 16, both domains: the band of the dense end is two points thick; fixed as a whole at its
  // depth, its zig-zag no longer folds the map at the edge.
  for (auto domain : {BoundaryDomain::Rectangle, BoundaryDomain::Disk}) {
    auto p = test::parameterize(c, 16, domain);
    ASSERT_EQ(p.loops.size(), 1u);
    MapCheck m = check_map(c.points, c.normals, p.nbrs, p.map.uv);
    EXPECT_EQ(m.foldovers, 0u) << (m.foldovers ? foldover_message(m, c.points) : "");
    std::printf("[ ramp 5:1 %s ] sigma1/sigma2 p50 %.3f p95 %.3f max %s\n", p.map.domain.c_str(),
                m.report["conformality"]["p50"].get<double>(), m.report["conformality"]["p95"].get<double>(),
                m.report["conformality"]["max"].dump().c_str());
  }
}

TEST(MapCheck, AnisotropicGridHasNoFoldovers) {
  // Spacing 1.0 along x, 0.2 along y (5:1), slightly jittered; k = 24 so that the neighbourhoods
  // reach the next columns.
  PointCloud c = test::jittered_grid(30, 20, 1.0, 0.2, 0.1, 35);
  auto p = test::parameterize(c, 24, BoundaryDomain::Rectangle);
  ASSERT_EQ(p.loops.size(), 1u);
  MapCheck m = check_map(c.points, c.normals, p.nbrs, p.map.uv);
  EXPECT_EQ(m.foldovers, 0u) << (m.foldovers ? foldover_message(m, c.points) : "");
  std::printf("[ grid 5:1 ] sigma1/sigma2 p50 %.3f p95 %.3f, width %.2f height %.2f\n",
              m.report["conformality"]["p50"].get<double>(), m.report["conformality"]["p95"].get<double>(),
              p.map.width, p.map.height);
}

TEST(MapCheck, AnisotropicGridAtK16HasNoFoldovers) {
  // The same 5:1 grid with k = 16, both domains.
  PointCloud c = test::jittered_grid(30, 20, 1.0, 0.2, 0.1, 35);
  for (auto domain : {BoundaryDomain::Rectangle, BoundaryDomain::Disk}) {
    auto p = test::parameterize(c, 16, domain);
    ASSERT_EQ(p.loops.size(), 1u);
    MapCheck m = check_map(c.points, c.normals, p.nbrs, p.map.uv);
    EXPECT_EQ(m.foldovers, 0u) << p.map.domain << ": " << (m.foldovers ? foldover_message(m, c.points) : "");
  }
}

TEST(MapCheck, RandomDiskAndRectangleHaveNoFoldovers) {
  // Uniform random samplings (the boundary is a band one or two points thick, the loop zig-zags
  // through it), k = 16, each patch on both domains.
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> ux(0, 40), uy(0, 25);
  PointCloud rect;
  for (int i = 0; i < 5000; ++i) {
    double x = ux(rng), y = uy(rng);
    rect.points.emplace_back(x, y, 2 * std::sin(x / 8) * std::cos(y / 10));
  }
  for (const auto& q : rect.points)
    rect.normals.push_back(Eigen::Vector3d(-0.25 * std::cos(q.x() / 8) * std::cos(q.y() / 10),
                                           0.2 * std::sin(q.x() / 8) * std::sin(q.y() / 10), 1)
                               .normalized());
  for (const PointCloud& c : {test::random_disk(5000, 20, 38), rect})
    for (auto domain : {BoundaryDomain::Rectangle, BoundaryDomain::Disk}) {
      auto p = test::parameterize(c, 16, domain);
      ASSERT_EQ(p.loops.size(), 1u);
      MapCheck m = check_map(c.points, c.normals, p.nbrs, p.map.uv);
      EXPECT_EQ(m.foldovers, 0u) << p.map.domain << ": " << (m.foldovers ? foldover_message(m, c.points) : "");
    }
}

TEST(MapCheck, Errors) {
  PointCloud c = test::random_disk(100, 10, 36);
  auto nb = compute_knn(c.points, 8);
  std::vector<Eigen::Vector2d> uv(99);
  EXPECT_THROW(check_map(c.points, c.normals, nb, uv), std::invalid_argument);
  uv.resize(100);
  try {
    check_map(c.points, {}, nb, uv);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the map check needs normals (the cloud has 0 normals for 100 points)");
  }
}

}  // namespace
}  // namespace scallop
