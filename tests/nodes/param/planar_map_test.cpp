// param.planar: the points' own xy, turned to the passes' direction, against closed forms.
#include "nodes/param/planar_map.h"

#include <gtest/gtest.h>

#include "engine/node.h"
#include "nodes/types/cloud.h"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace scallop {
namespace {

// Random points over the ellipse x^2 / 30^2 + y^2 / 10^2 <= 1 turned by `turn` degrees, z
// anything (a height field's), with a loop of 3 of them.
std::vector<Eigen::Vector3d> turned_ellipse(double turn) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  const double a = turn * std::numbers::pi / 180;
  std::vector<Eigen::Vector3d> P;
  while (P.size() < 4000) {
    const double x = 30 * u(rng), y = 10 * u(rng);
    if ((x / 30) * (x / 30) + (y / 10) * (y / 10) > 1) continue;
    P.emplace_back(std::cos(a) * x - std::sin(a) * y, std::sin(a) * x + std::cos(a) * y, 0.3 * x + 5 * u(rng));
  }
  return P;
}

TEST(PlanarMap, IsTheXyTurnedToThePassesDirectionOverItsBoundingRectangle) {
  const auto P = turned_ellipse(0);
  const UVMap m = planar_map(P, {0, 1, 2}, 90);  // passes along +y: u = x, v = y
  EXPECT_EQ(m.domain, "planar");
  ASSERT_EQ(m.uv.size(), P.size());
  double xmin = INFINITY, ymin = INFINITY, xmax = -INFINITY, ymax = -INFINITY;
  for (const auto& p : P) xmin = std::min(xmin, p.x()), ymin = std::min(ymin, p.y()), xmax = std::max(xmax, p.x()), ymax = std::max(ymax, p.y());
  for (std::size_t i = 0; i < P.size(); ++i) {
    EXPECT_NEAR(m.uv[i].x(), P[i].x() - xmin, 1e-9) << i;
    EXPECT_NEAR(m.uv[i].y(), P[i].y() - ymin, 1e-9) << i;
  }
  EXPECT_NEAR(m.width, xmax - xmin, 1e-9);
  EXPECT_NEAR(m.height, ymax - ymin, 1e-9);
  EXPECT_EQ(m.outer_loop, (std::vector<int>{0, 1, 2}));
  ASSERT_EQ(m.boundary_uv.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(m.boundary_uv[k], m.uv[k]);
  EXPECT_TRUE(m.corners.empty());
  // passes along +x: v = x, and u = -y keeps (u, v) turning the way (x, y) does
  const UVMap mx = planar_map(P, {0, 1, 2}, 0);
  for (std::size_t i = 0; i < P.size(); i += 97) {
    EXPECT_NEAR(mx.uv[i].x(), ymax - P[i].y(), 1e-9) << i;
    EXPECT_NEAR(mx.uv[i].y(), P[i].x() - xmin, 1e-9) << i;
  }
}

TEST(PlanarMap, AutomaticallyThePassesRunThePatchsShortWay) {
  // The ellipse's long axis turned to 30 degrees: the passes (along v) run across it, at 120,
  // so u runs along it and the rectangle is about 60 long and 20 across.
  const auto P = turned_ellipse(30);
  const UVMap m = planar_map(P, {0, 1, 2});
  EXPECT_NEAR(m.width, 60, 0.5);
  EXPECT_NEAR(m.height, 20, 0.5);
  // distances are kept (a rotation and a shift)
  for (std::size_t i = 1; i < P.size(); i += 131)
    EXPECT_NEAR((m.uv[i] - m.uv[0]).norm(), (P[i] - P[0]).head<2>().norm(), 1e-9) << i;
}

TEST(PlanarMap, RefusesWhatIsNoPatchSeenFromAbove) {
  auto message = [](const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop) {
    try {
      planar_map(P, loop);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::vector<Eigen::Vector3d> line{{0, 0, 0}, {1, 1, 5}, {2, 2, 1}, {3, 3, 0}};
  EXPECT_EQ(message(line, {0, 1, 2}).rfind("the points span no area in xy", 0), 0u) << message(line, {0, 1, 2});
  const std::vector<Eigen::Vector3d> tri{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(message(tri, {0, 1}), "the outer loop has 2 points; it needs at least 3");
  EXPECT_EQ(message(tri, {0, 1, 7}), "the outer loop names point 7; the cloud has 3");
  EXPECT_EQ(message({{0, 0, 0}, {1, 0, 0}}, {0, 1, 0}), "a planar map needs at least 3 points (got 2)");
  EXPECT_EQ(message({{0, 0, 0}, {1, 0, NAN}, {0, 1, 0}}, {0, 1, 2}), "point 1 has a NaN or infinite coordinate");
}

}  // namespace

namespace param_nodes {
NodeDecl make_planar_node();
}

TEST(PlanarNode, MapsTheCloudByItsOuterLoopAndSaysWhatIsMissing) {
  const NodeDecl d = param_nodes::make_planar_node();
  EXPECT_EQ(d.type, "param.planar");
  EXPECT_EQ(d.find_output("map")->type, "UVMap");
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = turned_ellipse(0);
  auto loops = std::make_shared<BoundaryLoops>();
  loops->loops = {{0, 1, 2}};
  NodeContext ctx(d, "planar", "part", {{"angle", 90.0}}, {{"cloud", cloud}, {"loops", loops}}, nullptr);
  d.run(ctx);
  const auto map = std::dynamic_pointer_cast<const UVMap>(ctx.take_outputs().at("map"));
  ASSERT_TRUE(map);
  EXPECT_EQ(map->domain, "planar");
  EXPECT_EQ(map->uv.size(), cloud->points.size());
  auto none = std::make_shared<BoundaryLoops>();
  NodeContext bad(d, "planar", "part", {{"angle", -1.0}}, {{"cloud", cloud}, {"loops", none}}, nullptr);
  try {
    d.run(bad);
    FAIL() << "no error";
  } catch (const NodeError& e) {
    EXPECT_STREQ(e.what(), "no boundary loop: run cloud.boundary_order first");
  }
}

}  // namespace scallop
