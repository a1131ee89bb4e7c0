#include "nodes/cloud/trim_steep.h"
#include "nodes/cloud/knn.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "engine/graph.h"
#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"

namespace scallop {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

// Uniform by area on the sphere of radius R, polar angles 0 .. theta_max (the slope of the
// sphere seen from +z is its polar angle).
std::vector<Vector3d> sphere_cap(double R, double theta_max_deg, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(std::cos(theta_max_deg * kPi / 180), 1.0), phi(0, 2 * kPi);
  std::vector<Vector3d> P(n);
  for (auto& p : P) {
    const double z = u(rng), f = phi(rng), s = std::sqrt(1 - z * z);
    p = R * Vector3d(s * std::cos(f), s * std::sin(f), z);
  }
  return P;
}

double polar_deg(const Vector3d& p) { return std::acos(p.z() / p.norm()) * 180 / kPi; }

// A cap of a sphere of radius 30 down to 84 degrees, trimmed at 70: what is kept is the cap down
// to 70 degrees; the trimmed band's area is 2 pi R^2 (cos 70 - cos 84) of 2 pi R^2 (1 - cos 84).
TEST(TrimSteep, SphereCapKeepsTheGentleCapAndMeasuresTheBand) {
  const double R = 30;
  const auto P = sphere_cap(R, 84, 20000, 1);
  TrimSteepOptions o;
  o.max_slope_deg = 70;
  const TrimSteepResult r = trim_steep(P, o);
  const double band = 2 * kPi * R * R * (std::cos(70 * kPi / 180) - std::cos(84 * kPi / 180));
  const double whole = 2 * kPi * R * R * (1 - std::cos(84 * kPi / 180));
  EXPECT_NEAR(r.area, whole, 0.05 * whole);
  EXPECT_NEAR(r.trimmed_area, band, 0.05 * band);
  std::size_t expect_kept = 0;
  for (const auto& p : P) expect_kept += polar_deg(p) <= 70;
  EXPECT_NEAR(static_cast<double>(r.kept.size()), expect_kept, 0.01 * expect_kept);
  for (std::size_t i : r.kept) EXPECT_LT(polar_deg(P[i]), 70.5);
  EXPECT_LE(r.max_slope_kept_deg, 70);
  // a few gentle points at the band's inner edge, whose nearest neighbour is steep and which no
  // gentle point has nearer than a steep one, are left with the band (6, of about 14 700 kept)
  EXPECT_LE(r.cut_off, 10u);
  ASSERT_EQ(r.regions.size(), 1u);  // the band is one ring
  EXPECT_NEAR(r.regions[0].area, r.trimmed_area, 1e-9);
  EXPECT_NEAR(r.regions[0].centroid.head<2>().norm(), 0, 1);
  EXPECT_GT(r.regions[0].max_slope_deg, 83);
  // nothing steeper than 90: nothing trimmed
  o.max_slope_deg = 90;
  EXPECT_EQ(trim_steep(P, o).kept.size(), P.size());
}

// Noise mixes steep and gentle estimates where the slope nears the limit: gentle points among
// steep ones beyond it, joined to the cap through a neighbour farther than their steep ones, were
// kept with it (47 points truly steeper than 72 degrees on these four clouds; the limit is 70).
// A gentle point is joined only to gentle neighbours nearer than its first steep one: 1 now.
TEST(TrimSteep, ANoisyCapKeepsLittleBeyondTheLimit) {
  const double R = 10, sigma = 0.02;
  int beyond = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const std::vector<Vector3d> T = sphere_cap(R, 85, 20000, seed);
    std::mt19937 rng(100 + seed);
    std::normal_distribution<double> noise(0, sigma);
    std::vector<Vector3d> P = T;
    for (auto& p : P) p += Vector3d(noise(rng), noise(rng), noise(rng));
    TrimSteepOptions o;
    o.max_slope_deg = 70;
    const TrimSteepResult r = trim_steep(P, o);
    for (std::size_t i : r.kept) beyond += polar_deg(T[i]) > 72;
    // nothing well inside the limit is lost
    std::vector<char> kept(P.size());
    for (std::size_t i : r.kept) kept[i] = 1;
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (polar_deg(T[i]) < 60) {
        EXPECT_TRUE(kept[i]) << "seed " << seed << " point " << i;
      }
    }
  }
  EXPECT_LE(beyond, 5);
}

// A steep wall across a plane cuts it in two: the larger gentle side is kept, the smaller one is
// cut off with the wall, and both are reported as one trimmed piece.
TEST(TrimSteep, AWallCutsOffTheSmallerSide) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ux(0, 40), uy(0, 30);
  std::vector<Vector3d> P;
  for (int i = 0; i < 12000; ++i) {
    const double x = ux(rng), y = uy(rng);
    // z rises 20 mm between x = 25 and 27 (slope atan(10) = 84 degrees)
    P.emplace_back(x, y, 10 * std::clamp(x - 25, 0.0, 2.0));
  }
  TrimSteepOptions o;
  o.max_slope_deg = 60;
  const TrimSteepResult r = trim_steep(P, o);
  std::size_t left = 0, right = 0;
  for (const auto& p : P) {
    if (p.x() < 24.5) ++left;
    if (p.x() > 27.5) ++right;
  }
  for (std::size_t i : r.kept) EXPECT_LT(P[i].x(), 25.5);
  EXPECT_GE(r.kept.size(), left);
  EXPECT_GE(r.cut_off, right);
  ASSERT_EQ(r.regions.size(), 1u);
  EXPECT_NEAR(r.regions[0].max.x(), 40, 0.5);
  EXPECT_NEAR(r.regions[0].min.x(), 25, 0.6);
}

TEST(TrimSteep, BadInputIsAnError) {
  const auto P = sphere_cap(10, 30, 100, 3);
  TrimSteepOptions o;
  o.max_slope_deg = 0;
  EXPECT_THROW(trim_steep(P, o), std::invalid_argument);
  o.max_slope_deg = 45;
  o.k = 2;
  EXPECT_THROW(trim_steep(P, o), std::invalid_argument);
  o.k = 16;
  EXPECT_THROW(trim_steep(std::vector<Vector3d>(P.begin(), P.begin() + 10), o), std::invalid_argument);
}

TEST(TrimSteep, ALineIsNamedOneDimensionalNotTrimmedAsSteep) {
  // a line with micron jitter: its normals tilt any way around it, 89 % was "trimmed as steep"
  std::vector<Vector3d> P;
  for (int i = 0; i <= 500; ++i) P.emplace_back(0.1 * i, i % 2 ? 0.001 : -0.001, i % 3 ? 0.0005 : 0.0);
  try {
    trim_steep(P, TrimSteepOptions{});
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the cloud is one-dimensional: its points lie along a line 50 mm long and 0.002 mm wide "
                           "(points 0.1 mm apart), not on a surface; scallop machines surface patches");
  }
}

TEST(TrimSteepNode, ItsParametersAreTrimSteepOptions) {
  // one default each, the struct's (its max_slope_deg was 75 while the node's was 90; 90, what
  // users got, is the struct's now)
  const NodeDecl& d = *builtin_registry().find("cloud.trim_steep");
  const TrimSteepOptions def;
  EXPECT_EQ(d.find_param("max_slope")->default_value, def.max_slope_deg);
  EXPECT_EQ(d.find_param("max_slope")->default_value, 90.0);
  EXPECT_EQ(d.find_param("k")->default_value, def.k);
  // a value out of the declared range is refused before anything runs, as any parameter's
  std::vector<std::string> errors;
  try {
    compile(parse_graph(R"({"scallop_graph": 1, "inputs": {"cloud": {"type": "File"}}, "nodes": [
        {"id": "read", "type": "io.read_cloud", "inputs": {"file": "@cloud"}},
        {"id": "trim", "type": "cloud.trim_steep", "params": {"max_slope": 95}, "inputs": {"cloud": "read.cloud"}}]})"),
            builtin_registry());
  } catch (const ValidationError& e) {
    errors = e.errors;
  }
  ASSERT_FALSE(errors.empty());  // (the graph input not given is the other error)
  EXPECT_EQ(errors[0], "nodes[1].params.max_slope: node 'trim': parameter 'max_slope' = 95 is out of range; "
                       "expected 1 .. 90 deg");
}

// The node run on `pc` with its defaults and `max_slope`: its outputs and what it said.
struct TrimNodeRun {
  std::map<std::string, ValuePtr> out;
  std::shared_ptr<const PointCloud> cloud;
  std::shared_ptr<const Report> report;
  std::vector<std::string> said;
};
TrimNodeRun run_trim_node(const PointCloud& pc, double max_slope) {
  const NodeDecl& d = *builtin_registry().find("cloud.trim_steep");
  nlohmann::json params;
  for (const auto& p : d.params) params[p.name] = p.default_value;
  params["max_slope"] = max_slope;
  TrimNodeRun r;
  NodeContext ctx(d, "trim", "cap", params, {{"cloud", std::make_shared<const PointCloud>(pc)}}, nullptr,
                  [&](const std::string& m) { r.said.push_back(m); });
  d.run(ctx);
  r.out = ctx.take_outputs();
  r.cloud = std::dynamic_pointer_cast<const PointCloud>(r.out.at("cloud"));
  r.report = std::dynamic_pointer_cast<const Report>(r.out.at("report"));
  return r;
}

TEST(TrimSteepNode, SaysWhatIsNotMachinedAndKeepsTheRest) {
  const NodeDecl& d = *builtin_registry().find("cloud.trim_steep");
  PointCloud pc;
  pc.points = sphere_cap(30, 84, 20000, 1);
  pc.uncertainty.assign(pc.points.size(), 0.01);
  nlohmann::json params;
  for (const auto& p : d.params) params[p.name] = p.default_value;
  params["max_slope"] = 70.0;
  const TrimNodeRun run = run_trim_node(pc, 70.0);
  const auto& [out, cloud, report, said] = run;
  ASSERT_TRUE(cloud && report);
  EXPECT_EQ(report->data["kept"], cloud->size());
  EXPECT_EQ(cloud->uncertainty.size(), cloud->size());
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0].rfind("not machined: " +
                              std::to_string(pc.size() - cloud->size()) + " points (",
                          0),
            0u)
      << said[0];
  EXPECT_NE(said[0].find("steeper than 70 degrees or cut off by them, in 1 piece;"), std::string::npos) << said[0];
  // the points not kept, in their order: what the guard keeps the ball clear of
  auto left_out = std::dynamic_pointer_cast<const PointCloud>(out.at("left_out"));
  ASSERT_TRUE(left_out);
  ASSERT_EQ(left_out->size() + cloud->size(), pc.size());
  std::size_t k = 0, l = 0;
  for (const auto& p : pc.points) {
    if (k < cloud->size() && cloud->points[k] == p) ++k;
    else if (l < left_out->size() && left_out->points[l] == p) ++l;
  }
  EXPECT_EQ(k, cloud->size());
  EXPECT_EQ(l, left_out->size());
  for (const auto& p : left_out->points) EXPECT_GT(polar_deg(p), 68);

  // its neighbours are cloud.knn's on the kept points: whether some were trimmed (computed
  // again on them) or none (the trim's own, handed on)
  auto nbrs = std::dynamic_pointer_cast<const Neighborhoods>(out.at("neighbors"));
  ASSERT_TRUE(nbrs);
  const Neighborhoods expect = compute_knn(cloud->points, 16);
  EXPECT_EQ(nbrs->k, 16);
  EXPECT_EQ(nbrs->indices, expect.indices);
  EXPECT_EQ(nbrs->sq_dists, expect.sq_dists);
  params["max_slope"] = 90.0;
  NodeContext all(d, "trim", "cap", params, {{"cloud", std::make_shared<const PointCloud>(pc)}}, nullptr);
  d.run(all);
  auto all_out = all.take_outputs();
  auto all_cloud = std::dynamic_pointer_cast<const PointCloud>(all_out.at("cloud"));
  auto all_nbrs = std::dynamic_pointer_cast<const Neighborhoods>(all_out.at("neighbors"));
  ASSERT_EQ(all_cloud->size(), pc.size());
  const Neighborhoods all_expect = compute_knn(pc.points, 16);
  EXPECT_EQ(all_nbrs->indices, all_expect.indices);
  EXPECT_EQ(all_nbrs->sq_dists, all_expect.sq_dists);

  // fewer points kept than neighbours asked for each: a clear error, not an empty graph
  PointCloud few;
  few.points = sphere_cap(30, 84, 300, 5);
  params["max_slope"] = 20.0;  // keeps 21 of these 300 points
  params["k"] = 64;
  NodeContext thin(d, "trim", "cap", params, {{"cloud", std::make_shared<const PointCloud>(few)}}, nullptr);
  try {
    d.run(thin);
    FAIL() << "no error";
  } catch (const NodeError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("only ", 0), 0u) << m;
    EXPECT_NE(m.find(" points are kept: the 64 nearest neighbours of each need more (raise max_slope or lower k)"),
              std::string::npos)
        << m;
  }
  params["k"] = 16;

  params["max_slope"] = 1.0;
  NodeContext none(d, "trim", "cap", params, {{"cloud", std::make_shared<const PointCloud>(pc)}}, nullptr);
  try {
    d.run(none);
    FAIL() << "no error";
  } catch (const NodeError& e) {
    EXPECT_NE(std::string(e.what()).find("are not steeper than 1 degrees: nothing left to machine from above (raise max_slope)"),
              std::string::npos)
        << e.what();
  }
}

std::string g4(double x) {  // as the node prints numbers
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", x);
  return b;
}

TEST(TrimSteepNode, APieceApartFromThePatchIsNamedApartNotSteep) {
  // A gentle cap and, 30 mm beyond it, a 6 x 6 grid of points (a clamp's top in the scan): no
  // point is steep, so raising max_slope would keep nothing more; the warning says the piece is
  // apart and what would machine it, word for word.
  PointCloud pc;
  pc.points = sphere_cap(30, 30, 4000, 3);
  for (int i = 0; i < 36; ++i) pc.points.emplace_back(50 + 0.3 * (i % 6), 0.3 * (i / 6), 0.0);
  const TrimNodeRun run = run_trim_node(pc, 75.0);
  const auto& [out, cloud, report, said] = run;
  ASSERT_TRUE(cloud && report);
  EXPECT_EQ(cloud->size(), 4000u);
  EXPECT_EQ(report->data["steep"], 0);
  EXPECT_EQ(report->data["cut_off"], 36);
  ASSERT_EQ(said.size(), 1u);
  const double area = report->data["trimmed_area_mm2"], whole = report->data["area_mm2"];
  EXPECT_EQ(said[0], "not machined: 36 points (" + g4(area) + " mm2, " + g4(100 * area / whole) +
                         " % of the area) apart from the largest connected piece, which is machined, in 1 "
                         "piece; the largest (" + g4(area) + " mm2) from x 50 to 51.5, y 0 to 1.5; not "
                         "connected to it through their 16 nearest neighbours: give such a piece as a part "
                         "of its own to machine it");
}

}  // namespace
}  // namespace scallop
