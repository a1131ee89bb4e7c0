#include "nodes/cloud/clean.h"

#include <gtest/gtest.h>

#include "tests/test_support.h"

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/node.h"

namespace scallop {
namespace {

using Eigen::Vector3d;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

PointCloud grid(int nx, int ny, double h) {
  PointCloud c;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) c.points.emplace_back(i * h, j * h, 0.01 * ((i * 7 + j * 3) % 5));
  return c;
}

TEST(Clean, DropsNonFiniteAndDuplicatesKeepingTheFirst) {
  PointCloud c;
  c.points = {{0, 0, 0},  {1, 0, 0}, {kNaN, 0, 0}, {0, 0, 0},  {2, 0, kInf},
              {1, 0, 0},  {0, 3, 0}, {0, 0, 0},    {0, -kInf, 0}, {5, 5, 5}};
  CleanStats s;
  const PointCloud out = clean_cloud(c, CleanOptions{}, &s);
  EXPECT_EQ(s.input, 10u);
  EXPECT_EQ(s.non_finite, 3u);
  EXPECT_EQ(s.duplicates, 3u);
  EXPECT_EQ(s.outliers, 0u);
  EXPECT_EQ(s.output, 4u);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out.points[0], Vector3d(0, 0, 0));
  EXPECT_EQ(out.points[1], Vector3d(1, 0, 0));
  EXPECT_EQ(out.points[2], Vector3d(0, 3, 0));
  EXPECT_EQ(out.points[3], Vector3d(5, 5, 5));
  EXPECT_FALSE(out.has_normals());
}

TEST(Clean, NaNNormalsDropThePointAndNormalsFollowTheirPoints) {
  PointCloud c;
  c.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 0, 0}, {3, 0, 0}};
  c.normals = {{0, 0, 1}, {0, kNaN, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, -1}};
  CleanStats s;
  CleanOptions in_order;
  in_order.spatial_order = false;
  const PointCloud out = clean_cloud(c, in_order, &s);
  EXPECT_EQ(s.non_finite, 1u);
  EXPECT_EQ(s.duplicates, 0u);  // point 3 duplicates point 1, which was already dropped
  ASSERT_EQ(out.size(), 4u);
  ASSERT_TRUE(out.has_normals());
  EXPECT_EQ(out.points[2], Vector3d(1, 0, 0));
  EXPECT_EQ(out.normals[2], Vector3d(1, 0, 0));
  EXPECT_EQ(out.normals[3], Vector3d(0, 0, -1));
}

TEST(Clean, SpatialOrderKeepsEveryPointWithItsNormal) {
  // Points of a line given backwards come out along it; each keeps its own normal.
  PointCloud c;
  for (int i = 9; i >= 0; --i) {
    c.points.emplace_back(i, 0, 0);
    c.normals.emplace_back(0, std::sin(i), std::cos(i));
  }
  const PointCloud out = clean_cloud(c, CleanOptions{});
  ASSERT_EQ(out.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(out.points[i], Vector3d(i, 0, 0));
    EXPECT_EQ(out.normals[i], Vector3d(0, std::sin(i), std::cos(i)));
  }
}

TEST(Clean, NegativeZeroIsADuplicateOfZero) {
  PointCloud c;
  c.points = {{0, 0, 0}, {-0.0, 0, 0}, {0, 1, 0}};
  CleanStats s;
  clean_cloud(c, CleanOptions{}, &s);
  EXPECT_EQ(s.duplicates, 1u);
}

TEST(Clean, OutlierRemovalRemovesFarPoints) {
  PointCloud c = grid(30, 30, 1.0);
  const std::size_t n = c.size();
  c.points.emplace_back(15, 15, 40);   // far above the middle
  c.points.emplace_back(-60, 10, 0);   // far to the side
  c.points.emplace_back(100, 100, 100);
  CleanOptions opts;
  opts.remove_outliers = true;
  opts.outlier_k = 8;
  opts.outlier_std_ratio = 2.0;
  opts.spatial_order = false;
  CleanStats s;
  const PointCloud out = clean_cloud(c, opts, &s);
  EXPECT_EQ(s.outliers, 3u);
  EXPECT_EQ(s.output, n);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(out.points[i], c.points[i]);
  // Off, the same cloud keeps everything.
  opts.remove_outliers = false;
  EXPECT_EQ(clean_cloud(c, opts).size(), n + 3);
}

TEST(Clean, OutlierRemovalFollowsTheMeanPlusRatioStdRule) {
  // Points on a line at x = 0, 1, 2, 3 and one at 10, k = 1: mean distances are
  // 1, 1, 1, 1, 7; mu = 11/5 = 2.2, sample std = sqrt((4 * 1.44 + 23.04) / 4) = sqrt(7.2).
  PointCloud c;
  c.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {10, 0, 0}};
  CleanOptions opts;
  opts.remove_outliers = true;
  opts.outlier_k = 1;
  // (7 - 2.2) / sqrt(7.2) = 1.7889: a ratio just below removes the far point, just above keeps it.
  opts.outlier_std_ratio = 1.78;
  EXPECT_EQ(clean_cloud(c, opts).size(), 4u);
  opts.outlier_std_ratio = 1.79;
  EXPECT_EQ(clean_cloud(c, opts).size(), 5u);
}

TEST(Clean, TooFewPointsForOutlierRemovalIsAnError) {
  PointCloud c;
  c.points = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {kNaN, 0, 0}, {2, 0, 0}};
  CleanOptions opts;
  opts.remove_outliers = true;
  opts.outlier_k = 3;
  try {
    clean_cloud(c, opts);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "outlier removal with outlier_k = 3 needs at least 4 points; the cloud has 3 after "
              "removing 1 NaN/Inf and 1 duplicate points");
  }
}

TEST(Clean, EmptyCloudGivesEmptyCloud) {
  CleanStats s;
  EXPECT_EQ(clean_cloud(PointCloud{}, CleanOptions{}, &s).size(), 0u);
  EXPECT_EQ(s.input, 0u);
  EXPECT_EQ(s.output, 0u);
}

}  // namespace
}  // namespace scallop

// ---- the node ----
namespace scallop {
namespace cloud_nodes {
NodeDecl make_clean_node();
}  // namespace cloud_nodes
using cloud_nodes::make_clean_node;
namespace {

using test::run_node;

std::string node_error(const nlohmann::json& params, std::shared_ptr<PointCloud> cloud) {
  try {
    run_node(make_clean_node(), params, {{"cloud", cloud}});
  } catch (const NodeError& e) {
    return e.what();
  }
  return "no exception";
}

TEST(CleanNode, CleansAndReports) {
  const NodeDecl d = make_clean_node();
  EXPECT_EQ(d.type, "cloud.clean");
  auto cloud = std::make_shared<PointCloud>(grid(20, 20, 1.0));
  cloud->points.push_back(cloud->points[5]);
  cloud->points.emplace_back(kNaN, 1, 2);
  cloud->points.emplace_back(10, 10, 50);
  std::string message;
  auto out = run_node(d, {{"remove_outliers", true}}, {{"cloud", cloud}}, &message);
  auto c = std::dynamic_pointer_cast<const PointCloud>(out.at("cloud"));
  ASSERT_TRUE(c);
  EXPECT_EQ(c->size(), 400u);
  EXPECT_EQ(message, "kept 400 of 403 points (1 were NaN/Inf, 1 duplicates, 1 outliers, 0 stray)");
}

TEST(CleanNode, WarnsHowManyNonFinitePointsItDropped) {
  const NodeDecl d = make_clean_node();
  auto cloud = std::make_shared<PointCloud>(grid(5, 4, 1.0));
  cloud->points.emplace_back(kNaN, 1, 2);
  cloud->points.emplace_back(1, kInf, 2);
  cloud->points.emplace_back(1, 2, -kInf);
  auto run = [&](std::shared_ptr<PointCloud> c) {
    std::vector<std::string> warnings;
    NodeContext ctx(d, "clean", "part", {{"remove_outliers", false}, {"outlier_k", 16}, {"outlier_std_ratio", 2.0},
                                         {"remove_stray", false}, {"stray_k", 16}, {"spatial_order", true},
                                         {"min_points", 10}},
                    {{"cloud", c}}, nullptr, [&](const std::string& m) { warnings.push_back(m); });
    d.run(ctx);
    return warnings;
  };
  EXPECT_EQ(run(cloud), std::vector<std::string>{"dropped 3 of 23 points with a NaN or infinite coordinate or normal"});
  cloud->points.resize(20);
  cloud->points.push_back(cloud->points[0]);  // a duplicate is no reason to warn
  EXPECT_TRUE(run(cloud).empty());
}

TEST(CleanNode, ErrorTexts) {
  EXPECT_EQ(node_error({}, std::make_shared<PointCloud>()), "the cloud is empty");
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {kInf, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_EQ(node_error({}, cloud),
            "cloud has 4 points after cleaning (1 were NaN/Inf, 1 duplicates, 0 outliers, 0 stray); at "
            "least 10 are needed");
  EXPECT_EQ(node_error({{"min_points", 4}}, cloud), "no exception");
  EXPECT_EQ(node_error({{"remove_outliers", true}}, cloud),
            "outlier removal with outlier_k = 16 needs at least 17 points; the cloud has 4 after "
            "removing 1 NaN/Inf and 1 duplicate points");
}

}  // namespace
}  // namespace scallop
