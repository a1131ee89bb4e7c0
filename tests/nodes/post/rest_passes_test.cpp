#include "nodes/post/rest_passes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/post/simulate_part.h"
#include "nodes/surface/setups.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;
constexpr double kR = 2, kH = 0.02, kE = 0.005;

// A 20 x 20 mm plate at z = 0 facing +z, open (its top face only), in 8 x 8 squares.
Mesh plate() {
  Mesh m;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) m.vertices.push_back(V(2.5 * i, 2.5 * j, 0));
  for (std::uint32_t j = 0; j < 8; ++j)
    for (std::uint32_t i = 0; i < 8; ++i) {
      const std::uint32_t a = j * 9 + i;
      m.add_face_range(std::array<std::uint32_t, 4>{a, a + 1, a + 10, a + 9});
    }
  return m;
}

Setup setup_along(const V& axis) {
  Setup s;
  s.name = "1";
  s.axis = axis;
  s.rotation = rotation_to_z(axis);
  s.translation.setZero();
  return s;
}

// Rows along x over x in [0, 10] only, 0.8 sqrt(8 r h) apart (cusps 0.64 h, under the 0.8 h a
// place is left at): half the plate finished.
Toolpath half_cut() {
  Toolpath t;
  t.tool_radius = kR, t.scallop_height = kH, t.chord_error = kE, t.pattern = "zigzag";
  const double w = 0.8 * std::sqrt(8 * kR * kH);
  for (double y = 0; y <= 20 + 1e-9; y += w) {
    ToolpathPass p;
    for (double x = 0; x <= 10 + 1e-9; x += 0.5) p.contact.push_back(V(x, y, 0)), p.normal.push_back(V(0, 0, 1));
    t.passes.push_back(p);
  }
  return t;
}

PartSetupCut part_frame_cut(const Setup& s, const Toolpath& t) {
  PartSetupCut cut;
  cut.name = s.name;
  for (const ToolpathPass& p : t.passes)
    for (std::size_t k = 0; k < p.contact.size(); ++k) {
      const V c = s.rotation.transpose() * (p.contact[k] + kR * p.normal[k] - s.translation);
      if (k > 0) cut.feed.push_back({cut.feed.back().b, c});
      else cut.feed.push_back({c, c});
    }
  return cut;
}

// One setup's cut with no pass.
std::vector<Toolpath> no_cut() {
  std::vector<Toolpath> cuts(1);
  cuts[0].tool_radius = kR, cuts[0].scallop_height = kH, cuts[0].chord_error = kE;
  return cuts;
}

RestOptions options() {
  RestOptions o;
  o.tool_radius = kR, o.scallop = kH, o.chord = kE;
  return o;
}

TEST(RestPasses, AHalfCutPlateIsFinishedByRestPassesWithinH) {
  const Mesh part = plate();
  std::vector<scallop::Setup> setups = {setup_along(V(0, 0, 1))};
  std::vector<Toolpath> cuts = {half_cut()};
  const std::size_t before = cuts[0].passes.size();
  const RestResult res = add_rest_passes(part, setups, cuts, options());
  EXPECT_NEAR(res.measured_area, 400, 1e-6);
  // The half not cut, less what the balls along x = 10 reach beyond it (sqrt(2 r 0.8 h) = 0.25 mm).
  EXPECT_GT(res.left_area_before, 190);
  EXPECT_LT(res.left_area_before, 196);
  EXPECT_EQ(res.left_area_after, 0);
  EXPECT_EQ(res.unreached_area, 0);
  EXPECT_GE(res.rounds, 1);
  EXPECT_EQ(cuts[0].passes.size(), before + res.passes[0]);
  EXPECT_GT(res.length[0], 100);

  // Every rest ball rests on the plate (centre r above it, or r from its edge), none inside.
  const MeshDistance distance(part);
  for (std::size_t k = before; k < cuts[0].passes.size(); ++k)
    for (std::size_t q = 0; q < cuts[0].passes[k].contact.size(); ++q) {
      const V c = cuts[0].passes[k].contact[q] + kR * cuts[0].passes[k].normal[q];
      EXPECT_NEAR(distance(c), kR, 1e-3);
      EXPECT_GT(c.z(), 0);
    }

  // The certificate's measure of the whole plate, edges included.
  PartSimulateOptions so;
  so.tool_radius = kR, so.scallop = kH, so.chord = kE;
  const Simulation sim = simulate_part(part, {part_frame_cut(setups[0], cuts[0])}, so);
  EXPECT_LE(sim.report["scallop_max"].get<double>(), 1.01 * kH);
  EXPECT_EQ(sim.report["uncut_fraction"].get<double>(), 0);
  EXPECT_LE(sim.report["gouge_max"].get<double>(), kE);

  // Without rest rounds nothing is added: the other half stays uncut.
  std::vector<Toolpath> plain = {half_cut()};
  RestOptions none = options();
  none.rounds = 0;
  const RestResult nothing = add_rest_passes(part, setups, plain, none);
  EXPECT_EQ(plain[0].passes.size(), before);
  EXPECT_EQ(nothing.passes[0], 0u);
  const Simulation half = simulate_part(part, {part_frame_cut(setups[0], plain[0])}, so);
  // Uncut: beyond the reach of the balls along x = 10 within 20 h (sqrt(2 r 20 h) = 1.26 mm).
  EXPECT_NEAR(half.report["uncut_fraction"].get<double>(), (10 - 1.26) / 20, 0.01);
}

TEST(RestPasses, APlaceNoSetupComesDownToGetsAClampingOfItsOwn) {
  // The plate faces +z; the only clamping comes down along -z, from under it.
  const Mesh part = plate();
  std::vector<scallop::Setup> setups = {setup_along(V(0, 0, -1))};
  std::vector<Toolpath> cuts = no_cut();
  RestOptions o = options();
  o.scallop = 0.1;  // a coarser raster: the whole plate is cut by it
  const RestResult res = add_rest_passes(part, setups, cuts, o);
  EXPECT_NEAR(res.left_area_before, 400, 1e-6);  // uncut everywhere
  EXPECT_EQ(res.new_setups, 1u);
  ASSERT_EQ(setups.size(), 2u);
  ASSERT_EQ(cuts.size(), 2u);
  EXPECT_GT(setups[1].axis.z(), 0.999);  // the lattice's direction nearest +z
  EXPECT_EQ(setups[1].name.substr(0, 9), "2: rest (");
  EXPECT_NEAR((setups[1].rotation * setups[1].axis - V(0, 0, 1)).norm(), 0, 1e-12);
  EXPECT_EQ(res.passes[0], 0u);
  EXPECT_GT(res.passes[1], 0u);
  EXPECT_EQ(res.left_area_after, 0);
  EXPECT_EQ(res.unreached_area, 0);
  EXPECT_FALSE(res.no_direction_left);
}

TEST(RestPasses, APlaceNoSetupComesDownToIsReportedUnreachedWithoutNewClampings) {
  const Mesh part = plate();
  std::vector<scallop::Setup> setups = {setup_along(V(0, 0, -1))};
  std::vector<Toolpath> cuts = no_cut();
  RestOptions o = options();
  o.max_new_setups = 0;
  const RestResult res = add_rest_passes(part, setups, cuts, o);
  EXPECT_NEAR(res.left_area_after, 400, 1e-6);
  EXPECT_NEAR(res.unreached_area, 400, 1e-6);
  ASSERT_FALSE(res.unreached_at.empty());
  EXPECT_NEAR(res.unreached_at.front().z(), 0, 1e-9);
  for (std::size_t a = 0; a < res.unreached_at.size(); ++a)
    for (std::size_t b = a + 1; b < res.unreached_at.size(); ++b)
      EXPECT_GE((res.unreached_at[a] - res.unreached_at[b]).norm(), 2 * kR);
  EXPECT_EQ(res.passes[0], 0u);
  EXPECT_TRUE(cuts[0].passes.empty());
  EXPECT_EQ(setups.size(), 1u);
  EXPECT_FALSE(res.no_direction_left);  // none was looked for: another clamping would help
}

// A closed 20 x 20 x 10 box but for a 10 x 10 hole in the middle of its top (a 4 x 4 grid of
// quads, the middle four left out): a 4 mm ball falls through it.
Mesh box_with_a_hole_in_its_top() {
  Mesh m;
  auto top = [](int i, int j) { return std::uint32_t(j * 5 + i); };
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) m.vertices.push_back(V(5.0 * i, 5.0 * j, 10));
  const std::uint32_t b = 25;  // the bottom's corners
  for (const V& v : {V(0, 0, 0), V(20, 0, 0), V(20, 20, 0), V(0, 20, 0)}) m.vertices.push_back(v);
  std::vector<std::vector<std::uint32_t>> faces;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      if (!((i == 1 || i == 2) && (j == 1 || j == 2))) faces.push_back({top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1)});
  faces.push_back({b, b + 3, b + 2, b + 1});
  faces.push_back({b, b + 1, top(4, 0), top(3, 0), top(2, 0), top(1, 0), top(0, 0)});
  faces.push_back({b + 1, b + 2, top(4, 4), top(4, 3), top(4, 2), top(4, 1), top(4, 0)});
  faces.push_back({b + 2, b + 3, top(0, 4), top(1, 4), top(2, 4), top(3, 4), top(4, 4)});
  faces.push_back({b + 3, b, top(0, 0), top(0, 1), top(0, 2), top(0, 3), top(0, 4)});
  const V centre(10, 10, 5);
  for (auto& f : faces) {  // wound counter-clockwise seen from outside
    V n = V::Zero(), mid = V::Zero();
    for (std::size_t k = 0; k < f.size(); ++k)
      n += m.vertices[f[k]].cross(m.vertices[f[(k + 1) % f.size()]]), mid += m.vertices[f[k]] / double(f.size());
    if (n.dot(mid - centre) < 0) std::reverse(f.begin(), f.end());
    m.add_face_range(f);
  }
  return m;
}

TEST(RestPasses, ABallThatFallsThroughAHoleIsLeftOut) {
  // The clamping leans 60 degrees: the balls tangent to the top by the hole's rim stand over the
  // hole, and some of the raster's balls fall through it onto the inside of the box.
  const Mesh part = box_with_a_hole_in_its_top();
  std::vector<scallop::Setup> setups = {setup_along(V(0, std::sin(1.0472), std::cos(1.0472)))};
  std::vector<Toolpath> cuts = no_cut();
  RestOptions o = options();
  o.scallop = 0.1, o.max_new_setups = 0, o.base_normal = V(0, 0, -1);
  const RestResult res = add_rest_passes(part, setups, cuts, o);
  EXPECT_GT(res.inside_drops, 0u);
  ASSERT_FALSE(cuts[0].passes.empty());
  const MeshDistance distance(part);
  for (const auto& pass : cuts[0].passes)
    for (std::size_t k = 0; k < pass.contact.size(); ++k) {
      const V c = setups[0].rotation.transpose() * (pass.contact[k] + kR * pass.normal[k] - setups[0].translation);
      const bool inside = c.x() > 0 && c.x() < 20 && c.y() > 0 && c.y() < 20 && c.z() > 0 && c.z() < 10;
      EXPECT_FALSE(inside) << c.transpose();
      EXPECT_GE(distance(c), kR - std::max(kE / 4, 1e-3) - 1e-9);
    }
}

TEST(RestPasses, BadToolOrCountsAreRefused) {
  const Mesh part = plate();
  std::vector<scallop::Setup> setups = {setup_along(V(0, 0, 1))};
  std::vector<Toolpath> cuts(1);
  RestOptions o = options();
  o.scallop = 3;  // above r
  EXPECT_THROW(add_rest_passes(part, setups, cuts, o), std::invalid_argument);
  std::vector<Toolpath> two(2);
  EXPECT_THROW(add_rest_passes(part, setups, two, options()), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
