#include "nodes/cloud/height_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "engine/node.h"
#include "nodes/cloud/knn.h"
#include "nodes/cloud/normals.h"
#include "nodes/io/read_cloud.h"
#include "nodes/types/document.h"

namespace scallop {

namespace cloud_nodes {
NodeDecl make_height_field_node();
}  // namespace cloud_nodes
using cloud_nodes::make_height_field_node;

namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

struct Sampled {
  std::vector<Vector3d> P, N;
  Neighborhoods nbrs;
};

// KNN (k = 16, as the shipped graphs) and PCA normals oriented up, as the graphs compute them.
Sampled prepare(std::vector<Vector3d> P) {
  Sampled s;
  s.P = std::move(P);
  s.nbrs = compute_knn(s.P, 16);
  s.N = estimate_normals(s.P, s.nbrs, NormalOrientation::Up);
  return s;
}

// Fibonacci points on the sphere |p| = R with polar angle (from +Z) in [0, theta_max]:
// near-uniform and deterministic.
std::vector<Vector3d> sphere_cap(double R, double theta_max, int n) {
  std::vector<Vector3d> P;
  const double golden = kPi * (3 - std::sqrt(5.0));
  const double z_min = std::cos(theta_max);
  for (int i = 0; i < n; ++i) {
    const double z = 1 - (1 - z_min) * (i + 0.5) / n;
    const double r = std::sqrt(1 - z * z), phi = golden * i;
    P.push_back(R * Vector3d(r * std::cos(phi), r * std::sin(phi), z));
  }
  return P;
}

// A flat grid [x0, x0 + w] x [y0, y0 + h] at height z with the given spacing.
std::vector<Vector3d> grid(double x0, double y0, double w, double h, double z, double step) {
  std::vector<Vector3d> P;
  for (double x = x0; x <= x0 + w + 1e-9; x += step)
    for (double y = y0; y <= y0 + h + 1e-9; y += step) P.push_back({x, y, z});
  return P;
}

TEST(HeightField, DomeCapPasses) {
  const auto s = prepare(sphere_cap(30, 50 * kPi / 180, 3000));
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(height_field_problem(st, limits), "");
  EXPECT_EQ(st.points, 3000u);
  EXPECT_EQ(st.component_sizes.size(), 1u);
  EXPECT_EQ(st.significant_components, 1);
  EXPECT_EQ(st.layered_points, 0u);
  EXPECT_EQ(st.steep_points, 0u);
  // PCA normals on the rim see a one-sided neighbourhood: slightly less steep than the surface.
  EXPECT_NEAR(st.max_slope_deg, 49, 1.5);
  EXPECT_NEAR(st.xy_max.x(), 30 * std::sin(50 * kPi / 180), 0.5);
  // Area of the cap 2 pi R^2 (1 - cos 50°) = 2019 mm^2 over 3000 points: about 0.8 mm apart.
  EXPECT_GT(st.spacing, 0.5);
  EXPECT_LT(st.spacing, 1.0);
}

TEST(HeightField, SteepCapAt70DegreesPasses) {
  const auto s = prepare(sphere_cap(25, 70 * kPi / 180, 4000));
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(height_field_problem(st, limits), "");
  EXPECT_EQ(st.layered_points, 0u);
  EXPECT_EQ(st.steep_points, 0u);
  EXPECT_NEAR(st.max_slope_deg, 69, 1.5);
  // The same cap with a 60° limit has too many steep points.
  HeightFieldLimits strict;
  strict.max_slope_deg = 60;
  const auto st60 = analyze_height_field(s.P, s.N, s.nbrs, strict);
  EXPECT_GT(st60.steep_points, 400u);
  EXPECT_EQ(height_field_problem(st60, strict).rfind("walls steeper than 60°: ", 0), 0u)
      << height_field_problem(st60, strict);
}

TEST(HeightField, ClosedSphereIsNotAHeightField) {
  const auto s = prepare(sphere_cap(20, kPi, 4000));
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  // The lower half lies under the upper half, less a band around the equator where the two
  // halves are within 2 spacings of the sphere's inside (|z| < 0.44 R): about 28 % of the points.
  EXPECT_GT(st.layered_points, 1000u);
  EXPECT_LT(st.layered_points, 2000u);
  EXPECT_LT(st.layered_example.z(), -10);  // the clearest case is near the bottom
  EXPECT_EQ(height_field_problem(st, limits),
            "not a height field seen from +Z: 1294 points (32 %) lie under other points of the "
            "cloud (a closed object, an overhang or several layers), e.g. near (-0.4, 0.1, "
            "-20.0) with a layer 40.0 mm above it; a 3-axis machine cannot reach them (a scan's stray points off the "
            "surface look the same: --set clean.remove_stray=true drops them)");
}

TEST(HeightField, ALineIsOneDimensionalBeforeAnythingElse) {
  // a line with micron jitter: its normals tilt any way, so "walls" or "layers" would be reported
  HeightFieldStats s;
  s.points = 200;
  s.spacing = 0.25;
  s.significant_components = 1;
  s.steep_points = 150;
  s.extents.length = 50, s.extents.width = 0.004;
  EXPECT_EQ(height_field_problem(s, HeightFieldLimits{}),
            "the cloud is one-dimensional: its points lie along a line 50 mm long and 0.004 mm wide (points 0.25 mm "
            "apart), not on a surface; scallop machines surface patches");
}

TEST(HeightField, TwoSeparatePatchesFail) {
  auto P = grid(0, 0, 30, 20, 0, 1.0);         // 31 x 21 = 651 points
  const auto Q = grid(50, 0, 20, 20, 3, 1.0);  // 21 x 21 = 441 points
  P.insert(P.end(), Q.begin(), Q.end());
  const auto s = prepare(P);
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  ASSERT_EQ(st.component_sizes.size(), 2u);
  EXPECT_EQ(st.component_sizes[0], 651u);
  EXPECT_EQ(st.component_sizes[1], 441u);
  EXPECT_EQ(st.component[0], 0);
  EXPECT_EQ(st.component.back(), 1);
  EXPECT_EQ(height_field_problem(st, limits),
            "the cloud has 2 separate parts (60 %, 40 % of the points, not linked in the "
            "16-nearest-neighbour graph; the second centred near (60.0, 10.0, 3.0)): scallop "
            "plans one patch at a time; split it or remove the others");
  HeightFieldLimits two;
  two.max_components = 2;
  EXPECT_EQ(height_field_problem(st, two), "");
}

TEST(HeightField, SpecksAreReportedNotCounted) {
  // A part is at least k + 1 = 17 points in a 16-nearest-neighbour graph.
  auto P = grid(0, 0, 60, 40, 0, 1.0);              // 61 x 41 = 2501 points
  const auto speck = grid(100, 100, 3, 4, 0, 1.0);  // 20 points (0.8 %) far away
  P.insert(P.end(), speck.begin(), speck.end());
  const auto s = prepare(P);
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(st.component_sizes.size(), 2u);
  EXPECT_EQ(st.significant_components, 1);
  EXPECT_EQ(st.speck_points, 20u);
  EXPECT_EQ(height_field_problem(st, limits), "");
  EXPECT_DOUBLE_EQ(st.xy_max.x(), 60);  // specks are outside the measured extent
}

// A sheet folded like a Z seen from the side (y is the extrusion): z = 0 for x in [0, 40], a
// half turn up to z = 10, back to x = 0 at z = 10, another half turn up to z = 20, then forward
// to x = 40. The lower two layers are under the top one.
std::vector<Vector3d> z_fold(double step) {
  std::vector<Eigen::Vector2d> curve;  // (x, z) by arc length
  auto line = [&](double xa, double xb, double z) {
    const int m = static_cast<int>(std::round(std::abs(xb - xa) / step));
    for (int i = 0; i < m; ++i) curve.push_back({xa + (xb - xa) * i / m, z});
  };
  auto turn = [&](double cx, double cz, double side) {  // half circle of radius 5
    const int m = static_cast<int>(std::round(5 * kPi / step));
    for (int i = 0; i < m; ++i) {
      const double a = -kPi / 2 + kPi * i / m;
      curve.push_back({cx + side * 5 * std::cos(a), cz + 5 * std::sin(a)});
    }
  };
  line(0, 40, 0);
  turn(40, 5, +1);
  line(40, 0, 10);
  turn(0, 15, -1);
  line(0, 40, 20);
  std::vector<Vector3d> P;
  for (const auto& c : curve)
    for (double y = 0; y <= 30 + 1e-9; y += step) P.push_back({c.x(), y, c.y()});
  return P;
}

TEST(HeightField, FoldedSheetIsNotAHeightField) {
  const auto s = prepare(z_fold(1.0));
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(st.significant_components, 1);
  // The bottom and the middle layer (40 x 31 points each) lie under the top one.
  EXPECT_GE(st.layered_points, 2 * 40 * 31 - 2 * 4 * 31);
  EXPECT_LE(st.layered_points, 2 * 40 * 31 + 2 * 16 * 31);
  EXPECT_LT(st.layered_example.z(), 10.5);
  const std::string problem = height_field_problem(st, limits);
  EXPECT_EQ(problem.rfind("not a height field seen from +Z: ", 0), 0u) << problem;
  EXPECT_NE(problem.find("a 3-axis machine cannot reach them"), std::string::npos) << problem;
}

TEST(HeightField, VerticalWallIsSteepNotLayered) {
  // A box corner: floor z = 0 for x in [0, 20], a vertical wall at x = 20 up to z = 20, a top
  // z = 20 for x in [20, 40]. Exactly one z per (x, y) except along the wall, which is steep.
  std::vector<Vector3d> P = grid(0, 0, 19, 20, 0, 1.0);
  for (double z = 0; z <= 20 + 1e-9; z += 1.0)
    for (double y = 0; y <= 20 + 1e-9; y += 1.0) P.push_back({20, y, z});
  const auto top = grid(21, 0, 19, 20, 20, 1.0);
  P.insert(P.end(), top.begin(), top.end());
  const auto s = prepare(P);
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(st.layered_points, 0u);
  EXPECT_GT(st.steep_points, 300u);  // the wall has 21 x 21 points, its corners are blurred
  EXPECT_NEAR(st.max_slope_deg, 90, 1e-6);
  EXPECT_EQ(height_field_problem(st, limits).rfind("walls steeper than 85°: ", 0), 0u);
}

TEST(HeightField, TooFewPointsAndBadInputs) {
  const auto s = prepare(grid(0, 0, 5, 5, 0, 1.0));  // 36 points
  const HeightFieldLimits limits;
  const auto st = analyze_height_field(s.P, s.N, s.nbrs, limits);
  EXPECT_EQ(height_field_problem(st, limits),
            "the cloud has 36 points; at least 100 are needed to describe a patch to machine");
  EXPECT_THROW(analyze_height_field(s.P, {}, s.nbrs, limits), std::invalid_argument);
  EXPECT_THROW(analyze_height_field({}, {}, Neighborhoods{}, limits), std::invalid_argument);
  auto bad = s.P;
  bad[3].z() = std::nan("");
  EXPECT_THROW(analyze_height_field(bad, s.N, s.nbrs, limits), std::invalid_argument);
  const auto other = compute_knn(grid(0, 0, 6, 6, 0, 1.0), 16);
  EXPECT_THROW(analyze_height_field(s.P, s.N, other, limits), std::invalid_argument);
}

TEST(HeightField, ComponentsAreLabelledLargestFirst) {
  Neighborhoods g;  // k = 1: 0-1, 2-3-4 (2 -> 3 only one way), 5 alone (a self loop)
  g.k = 1;
  g.indices = {1, 0, 3, 4, 3, 5};
  g.sq_dists.assign(6, 1.0);
  std::vector<std::size_t> sizes;
  const auto label = knn_components(g, sizes);
  EXPECT_EQ(sizes, (std::vector<std::size_t>{3, 2, 1}));
  EXPECT_EQ(label, (std::vector<int>{1, 1, 0, 0, 0, 2}));
}

std::map<std::string, ValuePtr> run_node(const nlohmann::json& params,
                                         std::map<std::string, ValuePtr> inputs) {
  const NodeDecl d = make_height_field_node();
  nlohmann::json p;
  for (const auto& pd : d.params) p[pd.name] = pd.default_value;
  for (const auto& [key, value] : params.items()) p[key] = value;
  NodeContext ctx(d, "n", "part", p, std::move(inputs), nullptr);
  d.run(ctx);
  return ctx.take_outputs();
}

TEST(HeightField, NodePassesTheCloudThroughAndReports) {
  const auto s = prepare(sphere_cap(30, 50 * kPi / 180, 3000));
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = s.P;
  cloud->normals = s.N;
  auto nbrs = std::make_shared<Neighborhoods>(s.nbrs);
  auto out = run_node({}, {{"cloud", cloud}, {"neighbors", nbrs}});
  EXPECT_EQ(out.at("cloud").get(), cloud.get());
  const auto report = std::dynamic_pointer_cast<const Report>(out.at("report"));
  ASSERT_TRUE(report);
  EXPECT_EQ(report->data["components"]["count"], 1);
  EXPECT_EQ(report->data["layered"]["points"], 0);
  EXPECT_NEAR(report->data["slope"]["max_deg"].get<double>(), 49, 1.5);
  EXPECT_GT(report->data["spacing_mm"].get<double>(), 0.5);
}

TEST(HeightField, NodeRefusesAClosedSphereAndACloudWithoutNormals) {
  const auto s = prepare(sphere_cap(20, kPi, 4000));
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = s.P;
  cloud->normals = s.N;
  auto nbrs = std::make_shared<Neighborhoods>(s.nbrs);
  try {
    run_node({}, {{"cloud", cloud}, {"neighbors", nbrs}});
    FAIL() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("not a height field seen from +Z: 1294 points", 0), 0u)
        << e.what();
  }
  auto bare = std::make_shared<PointCloud>();
  bare->points = s.P;
  try {
    run_node({}, {{"cloud", bare}, {"neighbors", nbrs}});
    FAIL() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()),
              "the cloud has no normals; compute them first (cloud.normals)");
  }
}

// The public test data in ../shared/data (see its PROVENANCE.md), scaled to tens of mm.
TEST(HeightField, RealDataHemispherePassesCamelheadAndMilkDoNot) {
  const std::string data = std::string(SCALLOP_SOURCE_DIR) + "/../shared/data";
  if (!std::filesystem::exists(data)) GTEST_SKIP() << "../shared/data not found";
  const HeightFieldLimits limits;
  auto check = [&](const std::string& file, double scale) {
    const auto s = prepare(read_cloud(data + "/" + file, scale).points);
    return analyze_height_field(s.P, s.N, s.nbrs, limits);
  };
  // Analytic cap z >= 0.098 of the unit sphere: a height field, slopes up to 84°.
  const auto hemi = check("hemisphere/hemisphere.off", 50);
  EXPECT_EQ(height_field_problem(hemi, limits), "");
  EXPECT_EQ(hemi.layered_points, 0u);
  EXPECT_GT(hemi.max_slope_deg, 80);
  // A head cut at the neck, standing along z: much of it is under the rest.
  const auto camel = check("camelhead/camelhead.off", 500);
  EXPECT_GT(camel.layered_points, camel.points / 5);
  EXPECT_EQ(height_field_problem(camel, limits).rfind("not a height field seen from +Z", 0), 0u);
  // A Kinect view of a box: in parallel projection along z (not the camera's perspective) a
  // near face at z = 361 mm lies under a farther one at z = 380 mm.
  const auto milk = check("milk_kinect/milk.pcd", 500);
  EXPECT_GT(milk.layered_points, 50u);
  EXPECT_LT(milk.layered_points, 300u);
  EXPECT_EQ(height_field_problem(milk, limits).rfind("not a height field seen from +Z", 0), 0u);
}

}  // namespace
}  // namespace scallop
