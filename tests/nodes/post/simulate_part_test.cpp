#include "nodes/post/simulate_part.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "engine/node.h"
#include "nodes/mesh/self_crossings.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/toolpath.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace post_nodes {
NodeDecl make_simulate_part_node();
}  // namespace post_nodes
namespace {

using V = Eigen::Vector3d;

// Straight passes along x over the top z = Z of the box [0, 20]^2 x [0, Z], ball centres r above
// it at y = y0, y0 + w, ..., y1, running 1 mm past the box on both ends.
std::vector<CentreSegment> top_passes(double y0, double y1, double w, double r, double Z) {
  std::vector<CentreSegment> out;
  for (double y = y0; y <= y1 + 1e-9; y += w) out.push_back({V(-1, y, Z + r), V(21, y, Z + r)});
  return out;
}

PartSimulateOptions options(double r, double h) {
  PartSimulateOptions o;
  o.tool_radius = r, o.scallop = h, o.chord = 0.01;
  return o;
}

PartSimulateOptions on_its_base(PartSimulateOptions o) {
  o.base_normal = V(0, 0, -1);
  return o;
}

// One setup cutting the box's whole top with passes 1 apart.
std::vector<PartSetupCut> top_setup(double r) {
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "top", cuts[0].feed = top_passes(0, 20, 1, r, 10);
  return cuts;
}

TEST(SimulatePart, TwoSetupsShareTheTopTheScallopIsTheClosedFormTheSidesAreUncut) {
  // The box 20 x 20 x 10 on its base (-z). Two setups each cut half of the top with passes w = 1
  // apart: between two passes the ball leaves r - sqrt(r² - (w/2)²); the sides are never
  // reached, so 800 of the 1200 mm² measured (the base's 400 are not) stay uncut.
  const double r = 3, h = 0.05, w = 1;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  std::vector<PartSetupCut> cuts(2);
  cuts[0].name = "front", cuts[0].feed = top_passes(0, 10, w, r, 10);
  cuts[1].name = "back", cuts[1].feed = top_passes(10, 20, w, r, 10);
  PartSimulateOptions o = options(r, h);
  o.base_normal = V(0, 0, -1);
  const Simulation sim = simulate_part(box, cuts, o);
  const auto& rep = sim.report;
  const double closed_form = r - std::sqrt(r * r - 0.25 * w * w);  // 0.04196
  EXPECT_NEAR(rep["scallop_max_interior"].get<double>(), closed_form, 1e-5);
  // ... standing on the top, midway between two passes
  const auto& at = rep["scallop_max_interior_at"];
  EXPECT_NEAR(at["z"].get<double>(), 10, 1e-9);
  EXPECT_NEAR(std::fmod(at["y"].get<double>(), w), 0.5 * w, 0.02);
  EXPECT_NEAR(rep["base_fraction"].get<double>(), 0.25, 1e-12);
  EXPECT_NEAR(rep["measured_fraction"].get<double>(), 0.75, 1e-12);
  EXPECT_NEAR(rep["uncut_fraction"].get<double>(), 2.0 / 3, 1e-10);
  EXPECT_NEAR(rep["surface_area"].get<double>(), 1600, 1e-7);
  EXPECT_EQ(rep["unreachable_fraction"].get<double>(), 0);
  EXPECT_LT(rep["gouge_max"].get<double>(), 1e-9);
  EXPECT_EQ(rep["rapids_through_part"], 0);
  EXPECT_NEAR(rep["setups"][0]["finished_fraction"].get<double>(), 1.0 / 6, 0.01);
  EXPECT_NEAR(rep["setups"][1]["finished_fraction"].get<double>(), 1.0 / 6, 0.01);
  EXPECT_EQ(rep["pass"], false);
  EXPECT_EQ(rep["fail_reasons"], nlohmann::json::array({"uncut fraction 0.6667 > 0"}));
  EXPECT_EQ(rep["worst"][0]["kind"], "uncut");
  ASSERT_EQ(sim.face.size(), sim.samples.size());
  for (std::size_t i = 0; i < sim.samples.size(); ++i)
    if (std::abs(sim.samples[i].z - 10) < 1e-9) EXPECT_FALSE(std::isnan(sim.samples[i].scallop)) << "a top sample is uncut";
}

// A failing interior maximum says where it is and over how much of the part: the same top cut
// for h = 0.03, which its cusps (0.04196) exceed along every pass; with the uncut sides, the area
// over 1.01 H is the report's fraction of the 1200 mm² measured.
TEST(SimulatePart, AFailingInteriorMaximumSaysWhereAndOverHowMuch) {
  const double r = 3, h = 0.03, w = 1;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "top", cuts[0].feed = top_passes(0, 20, w, r, 10);
  const nlohmann::json rep = simulate_part(box, cuts, on_its_base(options(r, h))).report;
  ASSERT_FALSE(rep["pass"].get<bool>());
  const std::string reason = rep["fail_reasons"][0];
  const auto& at = rep["scallop_max_interior_at"];
  EXPECT_NEAR(at["z"].get<double>(), 10, 1e-9);
  const double over = rep["frac_over_limit"].get<double>() * 1200;
  EXPECT_GT(over, 800);  // the sides, and the cusps' crests on the top
  char expected[300];
  std::snprintf(expected, sizeof expected,
                "interior scallop max %.4g > 1.01 H (whole part %.4g) at (%.3f, %.3f, %.3f); %.4g mm² over 1.01 H or "
                "uncut, %.3g %% of the measured area",
                rep["scallop_max_interior"].get<double>(), rep["scallop_max"].get<double>(), at["x"].get<double>(),
                at["y"].get<double>(), at["z"].get<double>(), over, 100 * over / 1200);
  EXPECT_EQ(reason, expected);
  // Where the programs found no clamping coming down to it (within 2 r of one of their unreached
  // places), the reason says so; farther, it does not.
  PartSimulateOptions o = on_its_base(options(r, h));
  o.unreached_at = {V(at["x"].get<double>() + 1.5 * r, at["y"].get<double>(), at["z"].get<double>())};
  o.unreached_area = 0.25;
  EXPECT_EQ(simulate_part(box, cuts, o).report["fail_reasons"][0].get<std::string>(),
            std::string(expected) + "; no clamping's axis comes down to it clear of the part (0.25 mm² such, "
                                    "post.setup_programs): another clamping would (rest_setups)");
  o.unreached_by_any_direction = true;
  EXPECT_EQ(simulate_part(box, cuts, o).report["fail_reasons"][0].get<std::string>(),
            std::string(expected) + "; no clamping's axis comes down to it clear of the part, nor any direction the "
                                    "rest search tried (0.25 mm² such, post.setup_programs): not for this tool on a "
                                    "3-axis machine");
  o.unreached_at[0].x() += r;
  EXPECT_EQ(simulate_part(box, cuts, o).report["fail_reasons"][0].get<std::string>(), expected);
}

// A mesh made from a cloud has its edges only near the part's: edge_uncertainty moves the
// interior's border nearer them, so that the interior holds the part's own (stricter, never
// laxer). The box's top cut from y = 2 on: the band below is left high, and more of it counts.
TEST(SimulatePart, EdgeUncertaintyBringsTheInteriorNearerTheEdges) {
  const double r = 3, h = 0.05, w = 1;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "top", cuts[0].feed = top_passes(2, 20, w, r, 10);
  PartSimulateOptions o = options(r, h);
  o.base_normal = V(0, 0, -1);
  const nlohmann::json exact = simulate_part(box, cuts, o).report;
  o.edge_uncertainty = 0.6;
  const nlohmann::json widened = simulate_part(box, cuts, o).report;
  const double nominal = std::sqrt(8 * r * h);
  EXPECT_NEAR(exact["margin"].get<double>(), nominal, 1e-12);
  EXPECT_NEAR(widened["margin"].get<double>(), nominal - 0.6, 1e-12);
  EXPECT_GT(widened["samples_interior"].get<double>(), exact["samples_interior"].get<double>());
  // the top at y = 0.5 (inside the widened interior only) is left higher than anywhere the exact
  // interior reaches
  EXPECT_GT(widened["scallop_max_interior"].get<double>(), exact["scallop_max_interior"].get<double>() + 0.1);
  EXPECT_EQ(widened["scallop_max"], exact["scallop_max"]);
  EXPECT_DOUBLE_EQ(widened["edge_uncertainty"].get<double>(), 0.6);
  // In mean edge lengths: the box's twelve edges, 4 x 20 + 4 x 20 + 4 x 10 mm, are 50/3 mm on average.
  o.edge_uncertainty = 0;
  o.edge_uncertainty_edges = 0.6 / (50.0 / 3);
  const nlohmann::json in_edges = simulate_part(box, cuts, o).report;
  EXPECT_NEAR(in_edges["edge_uncertainty"].get<double>(), 0.6, 1e-12);
  EXPECT_NEAR(in_edges["margin"].get<double>(), nominal - 0.6, 1e-12);
  EXPECT_EQ(in_edges["scallop_max_interior"], widened["scallop_max_interior"]);
  o.edge_uncertainty = 0.7;  // the larger of the two counts
  EXPECT_NEAR(simulate_part(box, cuts, o).report["margin"].get<double>(), nominal - 0.7, 1e-12);
}

// The part sticks out of its mesh where a cloud's point says so (an edge left bevelled): a ball
// passing through that point has cut it away, though the mesh shows no gouge. The top is cut by
// passes 1 apart (centres at z = 10 + r, over y = 10); a point 0.03 above the top under a pass is
// 0.03 inside its ball; points on the top are touched, not cut; one far above every ball is not.
TEST(SimulatePart, ACloudPointInsideABallIsAGougeTheMeshCannotShow) {
  const double r = 3;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  const std::vector<PartSetupCut> cuts = top_setup(r);
  const PartSimulateOptions o = on_its_base(options(r, 0.05));
  const std::vector<Eigen::Vector3d> cloud = {V(5, 5, 10), V(15, 12, 10), V(10, 10, 10.03), V(10, 10.5, 20)};
  const nlohmann::json mesh_only = simulate_part(box, cuts, o).report;
  const nlohmann::json rep = simulate_part(box, cuts, o, {}, nullptr, nullptr, &cloud).report;
  EXPECT_LT(mesh_only["gouge_max"].get<double>(), 1e-9);
  EXPECT_FALSE(mesh_only.contains("gouge_max_cloud"));
  EXPECT_NEAR(rep["gouge_max_cloud"].get<double>(), 0.03, 1e-9);
  EXPECT_NEAR(rep["gouge_max"].get<double>(), 0.03, 1e-9);
  EXPECT_EQ(rep["cloud_points_cut"], 1);
  EXPECT_NEAR(rep["gouge_cloud_at"]["z"].get<double>(), 10.03, 1e-12);
  EXPECT_FALSE(rep["pass"].get<bool>());
  const auto& reasons = rep["fail_reasons"];  // the sides are uncut too
  EXPECT_NE(std::find(reasons.begin(), reasons.end(),
                      "1 point(s) of the cloud inside a ball, up to 0.03 deep at (10.000, 10.000, 10.030)"),
            reasons.end())
      << reasons;
  // The same points all on the top: nothing cut away.
  const std::vector<Eigen::Vector3d> on_top = {V(5, 5, 10), V(10, 10, 10)};
  const nlohmann::json clean = simulate_part(box, cuts, o, {}, nullptr, nullptr, &on_top).report;
  EXPECT_LT(clean["gouge_max_cloud"].get<double>(), 1e-9);
  EXPECT_EQ(clean["cloud_points_cut"], 0);
  EXPECT_TRUE(clean["gouge_cloud_at"].is_null());
  EXPECT_EQ(clean["pass"], mesh_only["pass"]);
}

TEST(SimulatePart, ACloudPointOutsideTheOuterMeshNearABallLeavesTheGougeUnbounded) {
  // The outer mesh is the box itself. A point 1.2 outside its side x = 20, 4.005 from the end of
  // a pass (more than r: not inside a ball, but within r + 1.2): the part stands out of the outer
  // mesh there, and what the ball cuts between the points is unknown. A point 1 under the base,
  // far from every pass, leaves the gouge bounded.
  const double r = 3;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  const std::vector<PartSetupCut> cuts = top_setup(r);
  const PartSimulateOptions o = on_its_base(options(r, 0.05));
  const std::vector<Eigen::Vector3d> cloud = {V(5, 5, 10), V(21.2, 10, 9), V(10, 10, -1)};
  const nlohmann::json rep = simulate_part(box, cuts, o, {}, &box, nullptr, &cloud).report;
  EXPECT_EQ(rep["cloud_points_cut"], 0);
  EXPECT_EQ(rep["gouge_unbounded_points"], 1);
  EXPECT_NEAR(rep["gouge_unbounded_max"].get<double>(), 1.2, 1e-9);
  EXPECT_NEAR(rep["gouge_unbounded_at"]["x"].get<double>(), 21.2, 1e-12);
  EXPECT_FALSE(rep["pass"].get<bool>());
  const auto& reasons = rep["fail_reasons"];
  EXPECT_NE(std::find(reasons.begin(), reasons.end(),
                      "1 point(s) of the cloud outside the outer mesh, up to 1.2 mm at (21.200, 10.000, 9.000), with a "
                      "ball passing within r + that: the gouge there is not bounded"),
            reasons.end())
      << reasons;
  // Without the point beside the pass, or without an outer mesh, nothing of it.
  const std::vector<Eigen::Vector3d> far = {V(5, 5, 10), V(10, 10, -1)};
  const nlohmann::json bounded = simulate_part(box, cuts, o, {}, &box, nullptr, &far).report;
  EXPECT_EQ(bounded["gouge_unbounded_points"], 0);
  EXPECT_TRUE(bounded["gouge_unbounded_at"].is_null());
  for (const auto& reason : bounded["fail_reasons"])
    EXPECT_EQ(reason.get<std::string>().find("not bounded"), std::string::npos) << reason;
  EXPECT_FALSE(simulate_part(box, cuts, o, {}, nullptr, nullptr, &cloud).report.contains("gouge_unbounded_points"));
}

TEST(SimulatePart, ABallBesideWhereTheMeshCrossesItselfIsNoGougeByTheFacesSeenFromBehind) {
  // The spiked cube's spike runs out of its bottom; beside it, below the bottom, a ball centre is
  // outside the part, but the spike's faces, nearest and seen from behind, read it 0.41 inside
  // by their normals: a gouge of r + 0.41 with nothing cut. The tangled faces' side is the rays'.
  std::set<std::size_t> spike;
  const Mesh part = test::spiked_cube(spike);
  const double r = 0.3;
  std::vector<PartSetupCut> beside(1);
  beside[0].name = "beside", beside[0].feed = {{V(1.5, 1.95, -0.6), V(1.5, 1.9, -0.6)}};
  const nlohmann::json rep = simulate_part(part, beside, options(r, 0.05), {}).report;
  EXPECT_LT(rep["gouge_max"].get<double>(), 0.01) << rep["gouge_max"];
  // With the outer mesh the part's own faces moved (here not at all), the same.
  EXPECT_LT(simulate_part(part, beside, options(r, 0.05), {}, &part).report["gouge_max"].get<double>(), 0.01);
}

TEST(SimulatePart, ABallPassingByWhereTheMeshCrossesItselfLeavesTheGougeUnbounded) {
  // The cube [0, 4]^3 with the middle of its top pulled through its bottom (a reconstruction
  // tangled at a gap finer than its points): a pass over the top at y = 2 comes by the spike's
  // faces, whatever the meshes say of the gouge there. The part may lie anywhere within half the
  // margin of them, so a ball centre within r + 3/4 of it of a sample fails the certificate.
  const double r = 1;
  std::set<std::size_t> spike;
  const Mesh part = test::spiked_cube(spike);
  const TangleKeepOut keep = tangle_keep_out(part, self_crossings(part));
  ASSERT_GT(keep.margin, 0);
  std::vector<PartSetupCut> near(1), beyond(1);
  near[0].name = "near", near[0].feed = {{V(-1, 2, 4 + r), V(5, 2, 4 + r)}};
  // A pass r + the whole margin beside the nearest sample: kept off as post.setup_programs keeps it.
  double top = -INFINITY;
  for (const V& q : keep.samples) top = std::max(top, q.z());
  beyond[0].name = "beyond", beyond[0].feed = {{V(-1, 2, top + r + keep.margin), V(5, 2, top + r + keep.margin)}};
  const PartSimulateOptions o = options(r, 0.05);
  const nlohmann::json rep = simulate_part(part, near, o, {}).report;
  EXPECT_GT(rep["crossing_pairs"].get<int>(), 0);
  EXPECT_GE(rep["tangled_faces"].get<std::size_t>(), spike.size());
  EXPECT_DOUBLE_EQ(rep["tangle_margin"].get<double>(), keep.margin);
  EXPECT_GE(rep["tangle_samples_reached"].get<std::size_t>(), 1u);
  EXPECT_FALSE(rep["tangle_reached_at"].is_null());
  EXPECT_FALSE(rep["pass"].get<bool>());
  const std::string prefix = "the part's mesh crosses itself (" + std::to_string(rep["crossing_pairs"].get<int>()) +
                             " face pairs, " + std::to_string(rep["tangled_faces"].get<int>()) + " faces tangled)";
  const auto& reasons = rep["fail_reasons"];
  EXPECT_NE(std::find_if(reasons.begin(), reasons.end(),
                         [&](const nlohmann::json& x) {
                           const std::string t = x.get<std::string>();
                           return t.rfind(prefix, 0) == 0 &&
                                  t.find(": the part there is not known, the gouge there is not bounded") != std::string::npos;
                         }),
            reasons.end())
      << reasons;
  const nlohmann::json away = simulate_part(part, beyond, o, {}).report;
  EXPECT_EQ(away["crossing_pairs"], rep["crossing_pairs"]);
  EXPECT_EQ(away["tangle_samples_reached"], 0);
  EXPECT_TRUE(away["tangle_reached_at"].is_null());
  for (const auto& reason : away["fail_reasons"])
    EXPECT_EQ(reason.get<std::string>().find("crosses itself"), std::string::npos) << reason;
  // The outer mesh's crossings are not counted (moved out, it crosses itself at concave edges);
  // a mesh that crosses nothing: none of it.
  const Mesh box = test::cube_mesh(4, 4.0);
  EXPECT_EQ(simulate_part(box, near, o, {}, &part).report["tangle_samples_reached"], 0);
  const nlohmann::json plain = simulate_part(box, near, o, {}).report;
  EXPECT_EQ(plain["crossing_pairs"], 0);
  EXPECT_EQ(plain["tangled_faces"], 0);
  EXPECT_EQ(plain["tangle_margin"], 0.0);
}

TEST(SimulatePart, GougesInsideAndNearAreMeasuredAndARapidThroughThePartIsCounted) {
  // A feed move through the middle of the box: its centre 5 below the top, r + 5 deep in the
  // material. Another setup dips 0.02 into the top and passes a corner outside (sqrt(12) > r
  // from it: no gouge there, though its nearest point is a corner, where the sign comes from the
  // rays' parity). A rapid crosses the box at mid height; another runs above it.
  const double r = 3;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  std::vector<PartSetupCut> cuts(2);
  cuts[0].name = "through";
  cuts[0].feed = {{V(10, 10, 5), V(10, 12, 5)}};
  cuts[0].rapid = {{V(-5, 10, 5), V(25, 10, 5)}, {V(-5, 10, 20), V(25, 10, 20)}};
  cuts[1].name = "dip";
  cuts[1].feed = {{V(5, 5, 10 + r), V(10, 10, 10 + r - 0.02)}, {V(10, 10, 10 + r - 0.02), V(15, 15, 10 + r)},
                  {V(22, 22, 12), V(22, 23, 12)}};
  const Simulation sim = simulate_part(box, cuts, options(r, 0.05));
  const auto& rep = sim.report;
  // the figures are upper bounds within 1e-5 of the truth, or a thousandth of how far the ball
  // is past the tolerance where that is more (8 um for this one, 8 mm in)
  const double through = rep["setups"][0]["gouge_max"], dip = rep["setups"][1]["gouge_max"];
  EXPECT_GE(through, r + 5);
  EXPECT_LE(through, r + 5 + 1e-3 * (r + 5 - 0.01) + 1e-12);
  EXPECT_GE(dip, 0.02 - 1e-12);
  EXPECT_LE(dip, 0.02 + 1e-5);
  EXPECT_EQ(rep["gouge_max"].get<double>(), through);
  EXPECT_EQ(rep["setups"][0]["rapids_through_part"], 1);
  EXPECT_EQ(rep["rapids_through_part"], 1);
  EXPECT_NEAR(rep["rapid_min_clearance"].get<double>(), -5 - r, 1e-3);
  EXPECT_EQ(rep["fail_reasons"][1].get<std::string>().substr(0, 13), "gouge max 8.0");
  EXPECT_EQ(rep["fail_reasons"][1].get<std::string>().substr(15), " > 0.01");
  // the deepest move leads the worst places, at its ball centre, named by its setup
  EXPECT_EQ(rep["worst"][0]["kind"], "gouge");
  EXPECT_EQ(rep["worst"][0]["at"], "ball centre");
  EXPECT_EQ(rep["worst"][0]["setup"], "through");
  EXPECT_EQ(rep["worst"][0]["value"].get<double>(), through);
  EXPECT_NEAR(rep["worst"][0]["x"].get<double>(), 10, 1e-9);
  EXPECT_NEAR(rep["worst"][0]["z"].get<double>(), 5, 1e-9);
  EXPECT_EQ(rep["worst"][1]["setup"], "dip");
  EXPECT_EQ(rep["fail_reasons"][3], "1 rapid(s) through the part");
}

TEST(SimulatePart, BetweenAnInnerAndAnOuterMeshScallopIsFromTheInnerGougeAgainstTheOuter) {
  // The real part is only known to lie between the box 10 high (inner) and 10.03 high (outer).
  // Passes w = 1 apart, their balls touching z = 10.02: the scallop above the inner top is the
  // closed form + 0.02 (the part may be that low); the outer top is 0.01 into the balls (it may be
  // that high). Without the outer mesh the balls gouge nothing.
  const double r = 3, w = 1;
  const Mesh inner = test::quad_box({1, 1, 1}, V(20, 20, 10)), outer = test::quad_box({1, 1, 1}, V(20, 20, 10.03));
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "top", cuts[0].feed = top_passes(0, 20, w, r, 10.02);
  PartSimulateOptions o = options(r, 0.1);
  o.base_normal = V(0, 0, -1);
  const auto both = simulate_part(inner, cuts, o, {}, &outer).report;
  const double closed_form = r - std::sqrt(r * r - 0.25 * w * w) + 0.02;
  EXPECT_NEAR(both["scallop_max_interior"].get<double>(), closed_form, 1e-5);
  EXPECT_GE(both["gouge_max"].get<double>(), 0.01 - 1e-12);
  EXPECT_LE(both["gouge_max"].get<double>(), 0.01 + 1e-5);
  const auto alone = simulate_part(inner, cuts, o).report;
  EXPECT_NEAR(alone["scallop_max_interior"].get<double>(), closed_form, 1e-5);
  EXPECT_LT(alone["gouge_max"].get<double>(), 1e-9);
  // Samples on the reconstruction (10.01 high), scallop traced from the same places of the inner
  // box: as from the inner box itself; from the reconstruction alone, 0.01 less.
  const Mesh made = test::quad_box({1, 1, 1}, V(20, 20, 10.01));
  const auto three = simulate_part(made, cuts, o, {}, &outer, &inner).report;
  EXPECT_NEAR(three["scallop_max_interior"].get<double>(), closed_form, 1e-5);
  EXPECT_NEAR(three["surface_area"].get<double>(), 2 * 400 + 4 * 20 * 10.01, 1e-7);  // the reconstruction's
  EXPECT_NEAR(simulate_part(made, cuts, o).report["scallop_max_interior"].get<double>(), closed_form - 0.01, 1e-5);
  const Mesh other = test::cube_mesh(2);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_part(made, cuts, o, {}, nullptr, &other); }),
            "the inner mesh is not the part's mesh with its vertices moved (its faces differ)");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] {
              const Mesh none;
              simulate_part(inner, cuts, o, {}, &none);
            }),
            "the outer mesh has no face");
}

TEST(SimulatePart, AChannelNarrowerThanTheBallIsUnreachableWithTheRadiusThatWouldReachIt) {
  // An open channel 2 mm wide, walls 10 high, floor at z = 0: a ball of radius 3 reaches none of
  // it. On the floor at x a ball of radius rho stands clear while min(x, 2 - x) >= rho - tol; on
  // a wall at height z, while min(z, 2 - rho, rho) >= rho - tol.
  Mesh channel;
  for (V p : {V(0, 0, 0), V(2, 0, 0), V(2, 20, 0), V(0, 20, 0), V(0, 0, 10), V(2, 0, 10), V(2, 20, 10), V(0, 20, 10)})
    channel.vertices.push_back(p);
  channel.add_face({0, 1, 2, 3});  // floor, +z
  channel.add_face({0, 3, 7, 4});  // x = 0, +x
  channel.add_face({1, 5, 6, 2});  // x = 2, -x
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "top", cuts[0].feed = {{V(1, -5, 30), V(1, 25, 30)}};
  const double tol = 0.01;
  const Simulation sim = simulate_part(channel, cuts, options(3, 0.05));
  const auto& rep = sim.report;
  EXPECT_NEAR(rep["unreachable_fraction"].get<double>(), 1, 1e-12);
  EXPECT_EQ(rep["fail_reasons"], nlohmann::json::array({"no interior sample was cut",
                                                         "nothing to measure: every sample is base or unreachable"}));
  ASSERT_GE(rep["unreachable"].size(), 3u);
  double previous = 0;
  for (const auto& place : rep["unreachable"]) {
    const double x = place["x"], z = place["z"], reach = place["reach_radius"];
    const double expected = z < 1e-9 ? std::min(x, 2 - x) + tol : std::min(1 + tol / 2, z + tol);
    // From below, to r / 32768.
    EXPECT_LE(reach, expected + 1e-9) << "at x " << x << ", z " << z;
    EXPECT_GE(reach, expected - 3.0 / 32768) << "at x " << x << ", z " << z;
    EXPECT_GE(reach, previous);  // the smallest first
    previous = reach;
  }
}

TEST(SimulatePart, BadInputIsNamed) {
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  std::vector<PartSetupCut> cuts(1);
  cuts[0].name = "1: +z", cuts[0].feed = top_passes(0, 20, 1, 3, 10);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_part(box, cuts, options(3, 3)); }),
            "the scallop limit 3 mm is not below the tool radius 3 mm");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_part(box, {}, options(3, 0.05)); }),
            "no setup to simulate");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_part(Mesh(), cuts, options(3, 0.05)); }),
            "the part's mesh has no face with an area");
  cuts[0].feed[0].b.x() = NAN;
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simulate_part(box, cuts, options(3, 0.05)); }),
            "setup '1: +z' has a ball centre that is not finite");
}

TEST(SimulatePart, TheNodeKeepsATangleMarginOnlyForAMeshMadeFromACloud) {
  // The spiked cube as the part, a pass over its top by the spike's faces: a mesh given as the
  // part (no cloud) is where the part is, crossing or not, and no margin fails the pass; the same
  // mesh made from a cloud (input cloud) keeps the reconstruction's margin, and the pass fails.
  const double r = 1;
  std::set<std::size_t> spike;
  const Mesh part = test::spiked_cube(spike);
  SetupPaths programs;
  SetupPath& s = programs.setups.emplace_back();
  s.name = "1: +z", s.file = "setup_1.ngc";
  s.path.tool_radius = r, s.path.scallop_height = 0.05, s.path.chord_error = 0.01;
  s.path.moves = {{MoveKind::Rapid, V(-1, 2, 4)}, {MoveKind::Feed, V(5, 2, 4)}};
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = part.vertices;
  std::map<std::string, ValuePtr> inputs{{"programs", std::make_shared<SetupPaths>(programs)},
                                         {"mesh", std::make_shared<Mesh>(part)}};
  const auto given = test::run_node(post_nodes::make_simulate_part_node(), {}, inputs);
  const auto& g = std::dynamic_pointer_cast<const Report>(given.at("report"))->data;
  EXPECT_GT(g["crossing_pairs"].get<int>(), 0);
  EXPECT_EQ(g["tangle_margin"].get<double>(), 0);
  EXPECT_EQ(g["tangle_samples_reached"].get<std::size_t>(), 0u);
  inputs["cloud"] = cloud;
  const auto made = test::run_node(post_nodes::make_simulate_part_node(), {}, inputs);
  const auto& m = std::dynamic_pointer_cast<const Report>(made.at("report"))->data;
  EXPECT_DOUBLE_EQ(m["tangle_margin"].get<double>(), tangle_keep_out(part, self_crossings(part)).margin);
  EXPECT_GE(m["tangle_samples_reached"].get<std::size_t>(), 1u);
  EXPECT_FALSE(m["pass"].get<bool>());
  // and a margin asked for
  inputs.erase("cloud");
  const auto asked = test::run_node(post_nodes::make_simulate_part_node(), {{"tangle_margin", 0.25}}, inputs);
  EXPECT_EQ(std::dynamic_pointer_cast<const Report>(asked.at("report"))->data["tangle_margin"].get<double>(), 0.25);
}

TEST(SimulatePart, TheNodeTakesEachProgramBackToThePartThroughItsPartToMachine) {
  // The box's top cut in a setup that stands the part on its base turned a quarter about z and
  // raised by 5: tips in the machine frame, taken back by R^T (tip + r z - t).
  const double r = 3, h = 0.05;
  const Mesh box = test::quad_box({1, 1, 1}, V(20, 20, 10));
  SetupPaths programs;
  SetupPath& s = programs.setups.emplace_back();
  s.name = "1: +z", s.file = "setup_1.ngc";
  s.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  s.translation = V(0, 0, 5);
  s.path.tool_radius = r, s.path.scallop_height = h, s.path.chord_error = 0.01;
  for (const CentreSegment& c : top_passes(0, 20, 1, r, 10)) {
    s.path.moves.push_back({MoveKind::Rapid, s.rotation * c.a + s.translation - V(0, 0, r)});
    s.path.moves.push_back({MoveKind::Feed, s.rotation * c.b + s.translation - V(0, 0, r)});
  }
  Report base;
  base.data = {{"base_direction", {0, 0, -1}}};
  auto out = test::run_node(post_nodes::make_simulate_part_node(), {},
                            {{"programs", std::make_shared<SetupPaths>(programs)},
                             {"mesh", std::make_shared<Mesh>(box)},
                             {"base", std::make_shared<Report>(base)}});
  const auto& rep = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_NEAR(rep["scallop_max_interior"].get<double>(), r - std::sqrt(r * r - 0.25), 1e-5);
  EXPECT_NEAR(rep["uncut_fraction"].get<double>(), 2.0 / 3, 1e-10);
  EXPECT_EQ(rep["setups"][0]["name"], "1: +z");
  EXPECT_NEAR(rep["setups"][0]["cut_length"].get<double>(), 21 * 22, 1e-9);
  EXPECT_NEAR(rep["setups"][0]["rapid_length"].get<double>(), 20 * std::hypot(22, 1), 1e-9);
  // one tool for the whole part
  SetupPaths two = programs;
  two.setups.push_back(programs.setups[0]);
  two.setups[1].name = "2: -z", two.setups[1].path.tool_radius = 2;
  EXPECT_EQ(test::error_of<NodeError>([&] {
              test::run_node(post_nodes::make_simulate_part_node(), {},
                             {{"programs", std::make_shared<SetupPaths>(two)}, {"mesh", std::make_shared<Mesh>(box)}});
            }),
            "setup '2: -z' uses a tool of radius 2 mm, the first 3 mm: one tool for the whole part");
}

}  // namespace
}  // namespace scallop
