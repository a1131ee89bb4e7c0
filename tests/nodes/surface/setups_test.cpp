#include "nodes/surface/setups.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "tests/nodes/surface/surface_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace surface_nodes {
NodeDecl make_setups_node();
}  // namespace surface_nodes

namespace {

using V = Eigen::Vector3d;

using test::flat_patch;

// The box [0, 40] x [0, 30] x [0, 12] without its bottom: top, then -x, +x, -y, +y.
Surfaces open_box() {
  Surfaces s;
  const double X = 40, Y = 30, Z = 12;
  s.patches.push_back(flat_patch({0, 0, Z}, {X, 0, Z}, {0, Y, Z}, {X, Y, Z}, {0, 0, 1}));
  s.patches.push_back(flat_patch({0, 0, 0}, {0, Y, 0}, {0, 0, Z}, {0, Y, Z}, {-1, 0, 0}));
  s.patches.push_back(flat_patch({X, 0, 0}, {X, Y, 0}, {X, 0, Z}, {X, Y, Z}, {1, 0, 0}));
  s.patches.push_back(flat_patch({0, 0, 0}, {X, 0, 0}, {0, 0, Z}, {X, 0, Z}, {0, -1, 0}));
  s.patches.push_back(flat_patch({0, Y, 0}, {X, Y, 0}, {0, Y, Z}, {X, Y, Z}, {0, 1, 0}));
  s.base_direction = {0, 0, -1};
  return s;
}

// The box's corners only (no faces): where it stands, nothing hidden.
Mesh box_corners() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(V(i & 1 ? 40 : 0, i & 2 ? 30 : 0, i & 4 ? 12 : 0));
  return m;
}

TEST(Setups, ABoxOnItsBaseNeedsFiveClampingsOneFacePerSetup) {
  const auto setups = plan_setups(open_box(), box_corners());
  ASSERT_EQ(setups.size(), 5u);
  const char* names[] = {"1: +z", "2: -x", "3: +x", "4: -y", "5: +y"};
  for (std::size_t s = 0; s < 5; ++s) {
    EXPECT_EQ(setups[s].name, names[s]);
    EXPECT_EQ(setups[s].patches, std::vector<std::uint32_t>{static_cast<std::uint32_t>(s)});
    EXPECT_NEAR(setups[s].min_normal_dot, 1.0, 1e-12);
    const Eigen::Matrix3d& R = setups[s].rotation;
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((R * setups[s].axis - V::UnitZ()).norm(), 1e-12);
  }
  // The top setup: the part as it stands, centred on x = y = 0, its bottom on the table.
  EXPECT_LT((setups[0].rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((setups[0].translation - V(-20, -15, 0)).norm(), 1e-12);
  // The -x setup: the face x = 0 faces the spindle and lies highest, the part's x = 40 on the table.
  const auto& mx = setups[1];
  EXPECT_NEAR((mx.rotation * V(0, 5, 5) + mx.translation).z(), 40.0, 1e-12);
  EXPECT_NEAR((mx.rotation * V(40, 5, 5) + mx.translation).z(), 0.0, 1e-12);
}

TEST(Setups, AtCompoundAnglesTwoClampingsCutTheBox) {
  // Two opposite corners of the box up: each axis meets the top and two sides, 1/sqrt(3) at best.
  const auto setups = plan_setups(open_box(), box_corners(), {.any_axis = true});
  ASSERT_EQ(setups.size(), 2u);
  EXPECT_EQ(setups[0].patches.size() + setups[1].patches.size(), 5u);
  EXPECT_GT(std::min(setups[0].min_normal_dot, setups[1].min_normal_dot), 0.2);
}

TEST(Setups, ATiltedFaceGoesWithTheTopWhenTheToolReachesIt) {
  // A flat top and a face tilted 30 degrees beside it: one clamping cuts both.
  Surfaces s;
  const double c = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
  s.patches.push_back(flat_patch({0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 0}, {0, 0, 1}));
  s.patches.push_back(flat_patch({10, 0, 0}, {10 + 10 * c, 0, -10 * sn}, {10, 10, 0}, {10 + 10 * c, 10, -10 * sn}, {sn, 0, c}));
  const auto setups = plan_setups(s, Mesh{});
  ASSERT_EQ(setups.size(), 1u);
  EXPECT_EQ(setups[0].name, "1: +z");
  EXPECT_EQ(setups[0].patches, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_NEAR(setups[0].min_normal_dot, c, 1e-12);
  EXPECT_EQ(setups[0].translation, V::Zero());
}

TEST(Setups, AFaceUnderAnOverhangNeedsAClampingThatSeesIt) {
  // The flat top and the face tilted 30 degrees of the test above, and a roof at z = 30 over
  // the tilted face (x from 10.5 to 19): +z no longer reaches it; along its own direction the
  // rays pass the roof's edge (at z = 30 they are beyond x = 27).
  Surfaces s;
  const double c = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
  s.patches.push_back(flat_patch({0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 0}, {0, 0, 1}));
  s.patches.push_back(
      flat_patch({10, 0, 0}, {10 + 10 * c, 0, -10 * sn}, {10, 10, 0}, {10 + 10 * c, 10, -10 * sn}, {sn, 0, c}));
  Mesh roof;
  roof.vertices = {{10.5, -1, 30}, {19, -1, 30}, {19, 11, 30}, {10.5, 11, 30}};
  roof.add_face({0, 3, 2, 1});
  const auto open = plan_setups(s, Mesh{});
  EXPECT_EQ(open.size(), 1u);
  const auto covered = plan_setups(s, roof);
  ASSERT_EQ(covered.size(), 2u);
  EXPECT_EQ(covered[0].name, "1: +z");
  EXPECT_EQ(covered[0].patches, std::vector<std::uint32_t>{0});
  EXPECT_EQ(covered[1].patches, std::vector<std::uint32_t>{1});
  EXPECT_EQ(covered[1].hidden_samples, 0u);
}

TEST(Setups, AWallSteeperThanTheLimitGetsItsOwnClamping) {
  // A wall at 85 degrees: n . z = cos 85 = 0.087, below the default 0.2, above 0.05.
  Surfaces s;
  const double t = 85 * M_PI / 180;
  const V n(std::sin(t), 0, std::cos(t));
  s.patches.push_back(flat_patch({0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 0}, {0, 0, 1}));
  s.patches.push_back(flat_patch({10, 0, 0}, {10 + 10 * std::cos(t), 0, -10 * std::sin(t)}, {10, 10, 0},
                           {10 + 10 * std::cos(t), 10, -10 * std::sin(t)}, n));
  // Its own direction is 5 degrees off +x: n . x = cos 5 = 0.9962 is within 0.005 of the best,
  // so the square +x clamping wins the tie (no protractor needed).
  const auto two = plan_setups(s, Mesh{});
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[1].name, "2: +x");
  EXPECT_NEAR(two[1].min_normal_dot, std::cos(5 * M_PI / 180), 1e-12);
  EXPECT_EQ(two[1].patches, std::vector<std::uint32_t>{1});
  const auto one = plan_setups(s, Mesh{}, {.min_normal_dot = 0.05});
  ASSERT_EQ(one.size(), 1u);
  EXPECT_NEAR(one[0].min_normal_dot, std::cos(t), 1e-12);
}

// A bore along x (radius 10, x from 0 to 20, wall in 36 flat faces) and, as a patch, the third
// of its wall at the bottom (angles 210 to 330 degrees, x from x0 to x1), faces and patch alike
// turned towards the bore's axis: its own direction is +z, where the bore's top is in the way.
std::pair<Surfaces, Mesh> bore_bottom(double x0 = 0, double x1 = 20) {
  const double R = 10, L = 20;
  const auto at = [&](double x, double deg) {
    const double t = deg * M_PI / 180;
    return V(x, R * std::cos(t), R * std::sin(t));
  };
  Mesh bore;
  for (int k = 0; k < 36; ++k) bore.vertices.push_back(at(0, 10 * k)), bore.vertices.push_back(at(L, 10 * k));
  for (std::uint32_t k = 0; k < 36; ++k) {
    const std::uint32_t a = 2 * k, b = 2 * ((k + 1) % 36);
    bore.add_face({a, a + 1, b + 1, b});
  }
  SurfacePatch p;
  p.surface.degree_u = p.surface.degree_v = 1;
  p.surface.poles_u = 13, p.surface.poles_v = 2;
  p.surface.knots_u = clamped_uniform_knots(13, 1);
  p.surface.knots_v = {0, 0, 1, 1};
  for (const double x : {x0, x1})
    for (int k = 0; k < 13; ++k) p.surface.poles.push_back(at(x, 210 + 10 * k));
  p.direction = V::UnitZ();
  Surfaces s;
  s.patches.push_back(p);
  return {s, bore};
}

TEST(Setups, ABoresWallHiddenFromItsOwnDirectionIsReachedFromTheBoresEnd) {
  const auto [surfaces, bore] = bore_bottom();
  // Nothing in the way: its own direction, +z.
  const auto open = plan_setups(surfaces, Mesh{});
  ASSERT_EQ(open.size(), 1u);
  EXPECT_EQ(open[0].name, "1: +z");
  // In the bore: tilted towards one of its ends, every sample reached, every normal at least the
  // threshold (min_normal_dot 0.2: the patch's best, cos 60 = 0.5, halved is more) from the axis.
  const auto tilted = plan_setups(surfaces, bore);
  ASSERT_EQ(tilted.size(), 1u);
  EXPECT_EQ(tilted[0].hidden_samples, 0u);
  EXPECT_GE(tilted[0].min_normal_dot, 0.2);
  EXPECT_GT(std::abs(tilted[0].axis.x()), 0.3);
  EXPECT_GT(tilted[0].axis.z(), 0.3);
  EXPECT_TRUE(tilted[0].hidden_patches.empty());
}

TEST(Setups, ABlindBoresWallIsReportedHiddenWithWhere) {
  // The bore closed at both ends: no direction reaches the wall (x from 2 to 18, clear of the
  // ends); the patch keeps its own, and the report and the node say what is hidden and where.
  auto [surfaces, bore] = bore_bottom(2, 18);
  for (const double x : {0.0, 20.0}) {
    const auto centre = static_cast<std::uint32_t>(bore.vertices.size());
    bore.vertices.push_back(V(x, 0, 0));
    for (std::uint32_t k = 0; k < 36; ++k) bore.add_face({centre, 2 * k + (x > 0), 2 * ((k + 1) % 36) + (x > 0)});
  }
  const auto setups = plan_setups(surfaces, bore);
  ASSERT_EQ(setups.size(), 1u);
  EXPECT_EQ(setups[0].name, "1: +z");
  EXPECT_EQ(setups[0].hidden_samples, 289u);
  ASSERT_EQ(setups[0].hidden_patches.size(), 1u);
  EXPECT_EQ(setups[0].hidden_patches[0].patch, 0u);
  EXPECT_EQ(setups[0].hidden_patches[0].samples, 289u);
  EXPECT_NEAR(setups[0].hidden_patches[0].at.x(), 10.0, 1e-9);
  EXPECT_NEAR(setups[0].hidden_patches[0].at.y(), 0.0, 1e-9);
  EXPECT_LT(setups[0].hidden_patches[0].at.z(), -8.0);
  std::vector<std::string> warnings;
  auto out = test::run_node(surface_nodes::make_setups_node(), nlohmann::json::object(),
                            {{"surfaces", std::make_shared<Surfaces>(surfaces)}, {"mesh", std::make_shared<Mesh>(bore)}},
                            nullptr, &warnings);
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_EQ(r["setups"][0]["hidden_patches"][0]["samples"], 289);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("setup '1: +z': the part hides 289 of 289 samples of patch 0 from this axis (around (10.00, "),
            std::string::npos);
}

TEST(Setups, ARotationTakesEveryAxisToZ) {
  for (const V& a : {V(0, 0, 1), V(0, 0, -1), V(1, 0, 0), V(0.6, 0, -0.8), V(1, 2, 3).normalized()}) {
    const Eigen::Matrix3d R = rotation_to_z(a);
    EXPECT_LT((R * a - V::UnitZ()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  }
}

TEST(Setups, BadInputIsNamed) {
  EXPECT_EQ(test::error_of<std::invalid_argument>([] { plan_setups(Surfaces{}, Mesh{}); }),
            "there are no patches to set up");
  Surfaces s = open_box();
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { plan_setups(s, Mesh{}, {.min_normal_dot = 0}); }),
            "min_normal_dot must lie in (0, 1]");
  s.patches[3].direction = V(0, 0, 0);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { plan_setups(s, Mesh{}); }),
            "patch 3: its direction is not a unit vector");
}

TEST(Setups, TheReportReadsBackAndABadOneIsNamed) {
  const auto planned = plan_setups(open_box(), box_corners());
  const auto back = setups_from_report({{"setups", setups_report(planned)}}, 5);
  ASSERT_EQ(back.size(), planned.size());
  for (std::size_t k = 0; k < back.size(); ++k) {
    EXPECT_EQ(back[k].name, planned[k].name);
    EXPECT_EQ(back[k].patches, planned[k].patches);
    EXPECT_LT((back[k].axis - planned[k].axis).norm(), 1e-12);
    EXPECT_EQ(part_to_machine(back[k]), part_to_machine(planned[k]));
  }
  const auto report = nlohmann::json::parse(
      R"({"setups": [{"name": "1: +z", "part_to_machine": [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "patches": [0]}]})");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { setups_from_report(report, 2); }),
            "setup '1: +z': part_to_machine's R is not a rotation");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { setups_from_report(nlohmann::json::object(), 2); }),
            "the setups report has no setups");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { setups_from_report({{"setups", setups_report(planned)}}, 3); }),
            "setup '4: -y': patch 3 of 3");
}

TEST(Setups, TheNodeReportsPartToMachineAsTheSetupsFileHasIt) {
  const Mesh part = box_corners();
  auto out = test::run_node(surface_nodes::make_setups_node(), nlohmann::json::object(),
                            {{"surfaces", std::make_shared<Surfaces>(open_box())}, {"mesh", std::make_shared<Mesh>(part)}});
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  ASSERT_EQ(r["setups"].size(), 5u);
  EXPECT_EQ(r["setups"][0]["name"], "1: +z");
  EXPECT_EQ(r["setups"][0]["part_to_machine"],
            nlohmann::json::parse("[[1, 0, 0, -20], [0, 1, 0, -15], [0, 0, 1, 0]]"));
  EXPECT_EQ(r["setups"][4]["patches"], nlohmann::json::parse("[4]"));
  EXPECT_EQ(test::error_of<NodeError>([] {
              test::run_node(surface_nodes::make_setups_node(), nlohmann::json::object(),
                             {{"surfaces", std::make_shared<Surfaces>()}});
            }),
            "surface.setups: there are no patches to set up");
}

}  // namespace
}  // namespace scallop
