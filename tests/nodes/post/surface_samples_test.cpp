// post.surface_samples (nodes/post/surface_grid.h): the certificate's surface samples, taken
// before the path; post.simulate given them certifies as it does sampling by itself.
#include "nodes/post/surface_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <sstream>

#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// z = a x over [0, 10] × [0, 12] from jittered points 0.25 apart, and its outline (the square's
// border points, counter-clockwise).
struct Plane {
  std::vector<Eigen::Vector3d> cloud;
  std::vector<Eigen::Vector2d> outline;
};
Plane tilted_plane(double a) {
  Plane p;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 48; ++j) {
      const bool border = i == 0 || j == 0 || i == 40 || j == 48;
      const double x = 0.25 * i + (border ? 0 : jitter(rng)), y = 0.25 * j + (border ? 0 : jitter(rng));
      p.cloud.emplace_back(x, y, a * x);
    }
  for (int i = 0; i < 40; ++i) p.outline.emplace_back(0.25 * i, 0);
  for (int j = 0; j < 48; ++j) p.outline.emplace_back(10, 0.25 * j);
  for (int i = 40; i > 0; --i) p.outline.emplace_back(0.25 * i, 12);
  for (int j = 48; j > 0; --j) p.outline.emplace_back(0, 0.25 * j);
  return p;
}

SurfaceGridOptions options_for(const Plane& p) {
  SurfaceGridOptions o;
  o.tool_radius = 3;
  o.scallop = 0.05;
  o.spacing = 0.1;
  o.loops = {p.outline};
  return o;
}

// Passes along y, 0.8 mm apart, on the plane z = a x.
Toolpath passes_on(double a) {
  Toolpath t;
  t.tool_radius = 3;
  t.scallop_height = 0.05;
  t.chord_error = 0.01;
  const Eigen::Vector3d n = Eigen::Vector3d(-a, 0, 1).normalized();
  for (double x = -0.4; x <= 10.4 + 1e-9; x += 0.8) {
    ToolpathPass pass;
    for (double y = -0.5; y <= 12.5 + 1e-9; y += 0.5) pass.contact.emplace_back(x, y, a * x), pass.normal.push_back(n);
    t.passes.push_back(pass);
  }
  return t;
}

// On a plane every sample is on it, with its normal, and the areas add up to the patch's: flat,
// one sample a node; at 60 degrees (1 / n_z = 2) each node's cell split 2 × 2, the areas then the
// slanted surface's (1 / n_z times its plan).
TEST(SurfaceSamples, AreThePlaneWithItsNormalAndTheirAreasAddUpToThePatchs) {
  for (const double a : {0.0, std::sqrt(3.0)}) {
    const Plane p = tilted_plane(a);
    const HeightFieldModel surf(p.cloud);
    const SurfaceSamples s = sample_surface_grid(surf, options_for(p));
    const Eigen::Vector3d n = Eigen::Vector3d(-a, 0, 1).normalized();
    double area = 0;
    for (const SurfacePoint& q : s.points) {
      EXPECT_NEAR(q.p.z(), a * q.p.x(), 1e-9);
      EXPECT_NEAR((q.n - n).norm(), 0, 1e-9);
      // (a split cell's samples spread up to half a spacing around its node, which is inside)
      EXPECT_TRUE(q.p.x() >= -0.05 && q.p.x() <= 10.05 && q.p.y() >= -0.05 && q.p.y() <= 12.05) << q.p.transpose();
      EXPECT_FALSE(q.beyond);
      EXPECT_NEAR(q.uncertainty, 0, 1e-12);
      area += q.weight;
    }
    const double slant = std::sqrt(1 + a * a);
    EXPECT_NEAR(area, 120 * slant, 0.005 * 120 * slant) << a;
    std::size_t on = 0;
    for (std::uint8_t c : s.inside) on += c == 1;
    EXPECT_EQ(s.points.size(), on * (a == 0 ? 1 : 4)) << a;
    ASSERT_EQ(s.row_start.size(), std::size_t(s.nodes) + 1);
    EXPECT_EQ(s.row_start.back(), s.points.size());
    EXPECT_EQ(s.spacing, 0.1);
    EXPECT_EQ(s.cloud_points, p.cloud.size());
  }
}

// The spacing is verify.py's, sqrt(8 r h) / 12, unless given; raised to keep within max_samples.
TEST(SurfaceSamples, TheSpacingIsAStepoverOverTwelveWithinMaxSamples) {
  const Plane p = tilted_plane(0);
  const HeightFieldModel surf(p.cloud);
  SurfaceGridOptions o = options_for(p);
  o.spacing = 0;
  EXPECT_DOUBLE_EQ(sample_surface_grid(surf, o).spacing, std::sqrt(8 * 3 * 0.05) / 12);
  o.max_samples = 1000;
  EXPECT_DOUBLE_EQ(sample_surface_grid(surf, o).spacing, std::sqrt(120.0 / 1000));
}

// Simulating at samples taken before is the same simulation, sample for sample.
TEST(SurfaceSamples, SimulatedAtThemTheCertificateIsTheSame) {
  const double a = 0.3;
  const Plane p = tilted_plane(a);
  const HeightFieldModel surf(p.cloud);
  SimulateOptions o;
  o.tool_radius = 3, o.scallop = 0.05, o.chord = 0.01, o.spacing = 0.1, o.loops = {p.outline};
  const auto feed = feed_centres(passes_on(a));
  const Simulation alone = simulate_cut(surf, feed, 0.0, o);
  const SurfaceSamples samples = sample_surface_grid(surf, surface_grid_options(o));
  const Simulation given = simulate_cut(surf, samples, feed, 0.0, o);
  EXPECT_EQ(alone.report.dump(), given.report.dump());
  ASSERT_EQ(alone.samples.size(), given.samples.size());
  for (std::size_t i = 0; i < alone.samples.size(); ++i) {
    EXPECT_EQ(alone.samples[i].x, given.samples[i].x);
    EXPECT_EQ(alone.samples[i].y, given.samples[i].y);
    EXPECT_TRUE(alone.samples[i].scallop == given.samples[i].scallop ||
                (std::isnan(alone.samples[i].scallop) && std::isnan(given.samples[i].scallop)));
    EXPECT_EQ(alone.samples[i].gouge, given.samples[i].gouge);
  }
  // the passes 0.8 apart in x, 0.8 sqrt(1 + a^2) along the plane, leave r - sqrt(r^2 - (half that)^2)
  const double half = 0.4 * std::sqrt(1 + a * a);
  EXPECT_NEAR(given.report["scallop_max_interior"].get<double>(), 3 - std::sqrt(9 - half * half), 1e-5);
}

// Samples taken for another limit or another cloud are refused, saying what differs.
TEST(SurfaceSamples, TakenForAnotherLimitOrCloudTheSimulationSaysSo) {
  const Plane p = tilted_plane(0);
  const HeightFieldModel surf(p.cloud);
  SimulateOptions o;
  o.tool_radius = 3, o.scallop = 0.05, o.chord = 0.01, o.spacing = 0.1, o.loops = {p.outline};
  const SurfaceSamples samples = sample_surface_grid(surf, surface_grid_options(o));
  const auto feed = feed_centres(passes_on(0));
  o.scallop = 0.04;
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_cut(surf, samples, feed, 0.0, o); }),
            "the surface samples were taken for r 3, h 0.05, spacing 0.1, max_samples 1500000, rim_band 0, 1 loops of "
            "176 points, this simulation is for r 3, h 0.04, spacing 0.1, max_samples 1500000, rim_band 0, 1 loops of "
            "176 points: take them with the same tool radius, scallop limit, spacing, max_samples, rim_band and loops");
  o.scallop = 0.05;
  std::vector<Eigen::Vector3d> fewer(p.cloud.begin(), p.cloud.end() - 1);
  const HeightFieldModel other(fewer);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_cut(other, samples, feed, 0.0, o); }),
            "the surface samples were taken from a cloud of 2009 points, this simulation's cloud has 2008");
}

TEST(SurfaceSamples, TheirBinaryFormReadsBackTheSame) {
  const Plane p = tilted_plane(std::sqrt(3.0));
  const HeightFieldModel surf(p.cloud);
  SurfaceGridOptions o = options_for(p);
  o.rim_band = 0.5;
  const SurfaceSamples s = sample_surface_grid(surf, o);
  std::ostringstream out;
  s.serialize(out);
  std::istringstream in(out.str());
  const auto back = std::dynamic_pointer_cast<const SurfaceSamples>(SurfaceSamples::deserialize(in));
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->options == s.options);
  EXPECT_EQ(back->inside, s.inside);
  EXPECT_EQ(back->row_start, s.row_start);
  EXPECT_EQ(back->rim_band, 0.5);
  ASSERT_EQ(back->points.size(), s.points.size());
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    EXPECT_EQ(back->points[i].p, s.points[i].p);
    EXPECT_EQ(back->points[i].weight, s.points[i].weight);
    EXPECT_EQ(back->points[i].beyond, s.points[i].beyond);
  }
  std::ostringstream again;
  back->serialize(again);
  EXPECT_EQ(again.str(), out.str());
  std::istringstream cut(out.str().substr(0, out.str().size() / 2));
  EXPECT_THROW(SurfaceSamples::deserialize(cut), std::runtime_error);
}

// The node, then post.simulate given its samples: the same report as post.simulate alone.
TEST(SurfaceSamplesNode, PostSimulateGivenItsSamplesCertifiesAsAlone) {
  const double a = 0.3;
  const Plane p = tilted_plane(a);
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = p.cloud;
  auto path = std::make_shared<Toolpath>(passes_on(a));
  const NodeDecl& samples_node = *builtin_registry().find("post.surface_samples");
  const NodeDecl& simulate = *builtin_registry().find("post.simulate");
  const auto taken = test::run_node(samples_node, {{"tool_radius", 3}, {"scallop_height", 0.05}, {"spacing", 0.1}},
                                    {{"cloud", cloud}});
  const auto given = test::run_node(simulate, {{"spacing", 0.1}},
                                    {{"path", path}, {"cloud", cloud}, {"samples", taken.at("samples")}});
  const auto alone = test::run_node(simulate, {{"spacing", 0.1}}, {{"path", path}, {"cloud", cloud}});
  const auto report = [](const std::map<std::string, ValuePtr>& out) {
    return std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  };
  EXPECT_EQ(report(given).dump(), report(alone).dump());
  // and given samples for another spacing, it says so
  EXPECT_NE(test::error_of<NodeError>([&] {
              test::run_node(simulate, {{"spacing", 0.2}}, {{"path", path}, {"cloud", cloud}, {"samples", taken.at("samples")}});
            }).find("the surface samples were taken for r 3, h 0.05, spacing 0.1"),
            std::string::npos);
}

TEST(SurfaceSamplesNode, WithoutTheLimitsItSaysWhatToGive) {
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = tilted_plane(0).cloud;
  const NodeDecl& node = *builtin_registry().find("post.surface_samples");
  EXPECT_EQ(test::error_of<NodeError>([&] { test::run_node(node, {{"tool_radius", 3}}, {{"cloud", cloud}}); }),
            "tool_radius and scallop_height must be given (> 0): the path's, which post.simulate judges against");
}

}  // namespace
}  // namespace scallop
