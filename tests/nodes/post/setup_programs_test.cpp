#include "nodes/post/setup_programs.h"
#include "nodes/post/keep_off_part.h"

#include <gtest/gtest.h>

#include <set>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "nodes/geom/bspline_surface.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/path/contour_grid.h"
#include "nodes/surface/setups.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/nodes/path/scallop_trace.h"
#include "tests/nodes/surface/surface_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// A 20 x 10 x 5 block standing on z = 0: its top and its front wall (y = 0) as patches, planned
// with contour grids, set up by plan_setups against the block's mesh.
struct Block {
  Surfaces surfaces;
  Mesh part;
  Toolpath path;
  std::vector<std::size_t> counts;
  std::vector<Setup> setups;

  Block() {
    surfaces.patches.push_back(test::flat_patch({0, 0, 5}, {20, 0, 5}, {0, 10, 5}, {20, 10, 5}, {0, 0, 1}));
    surfaces.patches.push_back(test::flat_patch({0, 0, 0}, {20, 0, 0}, {0, 0, 5}, {20, 0, 5}, {0, -1, 0}));
    for (int i = 0; i < 8; ++i) part.vertices.push_back(V(i & 1 ? 20 : 0, i & 2 ? 10 : 0, i & 4 ? 5 : 0));
    for (auto f : {std::array<std::uint32_t, 4>{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2},
                   {1, 3, 7, 5}})
      part.add_face_range(f);
    ContourGridOptions o;
    o.tool_radius = 2, o.scallop_height = 0.05, o.chord_error = 0.01;
    path.tool_radius = 2, path.scallop_height = 0.05, path.chord_error = 0.01, path.pattern = "contour_grid";
    for (const auto& sp : surfaces.patches) {
      const ContourGridResult g = plan_contour_grid(BSplinePatch(sp.surface, sp.direction), o);
      counts.push_back(g.passes.size());
      path.passes.insert(path.passes.end(), g.passes.begin(), g.passes.end());
    }
    setups = plan_setups(surfaces, part);
  }
};

// The tool-tip points of a program's G0/G1 moves.
std::vector<V> tips(const std::string& gcode) {
  std::vector<V> out;
  V at(0, 0, 0);
  std::istringstream in(gcode);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("G0 ", 0) != 0 && line.rfind("G1 ", 0) != 0) continue;  // not G17, G21, ...
    if (line.find_first_of("XYZ") == std::string::npos) continue;
    for (char axis : {'X', 'Y', 'Z'}) {
      const auto k = line.find(axis);
      if (k != std::string::npos) at[axis - 'X'] = std::stod(line.substr(k + 1));
    }
    out.push_back(at);
  }
  return out;
}

// For each move k - 1 -> k of a program's tool tips t, the least distance from the part of the
// ball's centre (radius r: the tip + r z) along it; entry 0 is unused (+infinity).
std::vector<double> move_clearances(const std::vector<V>& t, const Mesh& part, double r) {
  const MeshDistance distance(part);
  std::vector<double> out(t.size(), INFINITY);
  for (std::size_t k = 1; k < t.size(); ++k) {
    V nearest;
    std::size_t evaluations = 0;
    out[k] = distance.least_along(t[k - 1] + V(0, 0, r), t[k] + V(0, 0, r), r / 8, r, 1e-5, nearest, evaluations, false);
  }
  return out;
}

// The box [0, X] x [0, Y] x [0, Z] on its base: top and four sides, a patch each.
Surfaces box_patches(double X, double Y, double Z) {
  Surfaces s;
  s.patches.push_back(test::flat_patch({0, 0, Z}, {X, 0, Z}, {0, Y, Z}, {X, Y, Z}, {0, 0, 1}));
  s.patches.push_back(test::flat_patch({0, 0, 0}, {0, Y, 0}, {0, 0, Z}, {0, Y, Z}, {-1, 0, 0}));
  s.patches.push_back(test::flat_patch({X, 0, 0}, {X, Y, 0}, {X, 0, Z}, {X, Y, Z}, {1, 0, 0}));
  s.patches.push_back(test::flat_patch({0, 0, 0}, {X, 0, 0}, {0, 0, Z}, {X, 0, Z}, {0, -1, 0}));
  s.patches.push_back(test::flat_patch({0, Y, 0}, {X, Y, 0}, {0, Y, Z}, {X, Y, Z}, {0, 1, 0}));
  s.base_direction = {0, 0, -1};
  return s;
}

// Contour grids (e = 0.01) on the first `planned` patches, none on the others.
void plan_patches(const Surfaces& s, double r, double h, std::size_t planned, Toolpath& path,
                  std::vector<std::size_t>& counts) {
  ContourGridOptions o;
  o.tool_radius = r, o.scallop_height = h, o.chord_error = 0.01;
  path.tool_radius = r, path.scallop_height = h, path.chord_error = 0.01;
  for (std::size_t p = 0; p < s.patches.size(); ++p) {
    if (p >= planned) {
      counts.push_back(0);
      continue;
    }
    const ContourGridResult g = plan_contour_grid(BSplinePatch(s.patches[p].surface, s.patches[p].direction), o);
    counts.push_back(g.passes.size());
    path.passes.insert(path.passes.end(), g.passes.begin(), g.passes.end());
  }
}

// The programs' feed moves as ball centres in the part's frame, read back from their G-code
// (p = R^T (q - t)).
std::vector<test::Segment> feed_centres(const std::vector<SetupProgram>& programs,
                                        const std::vector<scallop::Setup>& setups, double r) {
  std::vector<test::Segment> moves;
  for (const SetupProgram& program : programs) {
    const scallop::Setup& setup = setups[program.setup];
    std::istringstream in(program.gcode);
    V at(0, 0, 0), prev(0, 0, 0);
    bool have = false;
    for (std::string line; std::getline(in, line);) {
      const bool feed = line.rfind("G1 ", 0) == 0, rapid = line.rfind("G0 ", 0) == 0;
      if (!feed && !rapid) continue;
      for (char axis : {'X', 'Y', 'Z'})
        if (const auto i = line.find(axis); i != std::string::npos) at[axis - 'X'] = std::stod(line.substr(i + 1));
      const V centre = setup.rotation.transpose() * (at + V(0, 0, r) - setup.translation);
      if (feed && have) moves.push_back({prev, centre});
      prev = centre, have = true;
    }
  }
  return moves;
}

// The largest scallop the moves leave on a 25 x 25 grid of every patch (sphere tracing along
// its normal); a place no move reaches counts as what traced_scallop gives it.
double worst_scallop(const Surfaces& s, const std::vector<test::Segment>& moves, double r) {
  double worst = 0;
  for (const auto& sp : s.patches) {
    const BSplinePatch face(sp.surface, sp.direction);
    for (int i = 0; i <= 24; ++i)
      for (int j = 0; j <= 24; ++j) {
        const SurfaceSample x = face({i / 24.0, j / 24.0});
        worst = std::max(worst, test::traced_scallop(x.position, x.normal, moves, r));
      }
  }
  return worst;
}

TEST(SetupPrograms, EachClampingCutsItsPatchFromAboveInItsOwnFrame) {
  const Block b;
  ASSERT_EQ(b.setups.size(), 2u);
  const auto programs = setup_programs(b.path, b.counts, b.setups, b.part, {}, {});
  ASSERT_EQ(programs.size(), 2u);
  EXPECT_EQ(programs[0].file, "setup_1.ngc");
  EXPECT_EQ(programs[0].passes, b.counts[0]);
  EXPECT_EQ(programs[1].passes, b.counts[1]);
  for (std::size_t s = 0; s < 2; ++s) {
    // In its machine frame the block's cut face is its top (z = its height there), and every
    // cutting tip lies on it: the ball touches the face from above.
    double top = -1e9;
    for (const V& p : b.part.vertices) top = std::max(top, (b.setups[s].rotation * p + b.setups[s].translation).z());
    EXPECT_NEAR(programs[s].clearance_z, top + 5, 1e-9);  // LinkOptions::safety
    std::size_t on_face = 0;
    double lowest = 1e9;
    for (const V& t : tips(programs[s].gcode)) on_face += std::abs(t.z() - top) < 1e-4, lowest = std::min(lowest, t.z());
    EXPECT_GE(on_face, 4 * programs[s].passes);  // each contour's four corners at least
    EXPECT_GT(lowest, top - 1e-4);                // nothing below the cut face
  }
  const nlohmann::json file = setups_file(programs, b.setups);
  EXPECT_EQ(file["format"], "scallop-setups/1");
  EXPECT_EQ(file["setups"][1]["gcode"], "setup_2.ngc");
  EXPECT_EQ(file["setups"][1]["part_to_machine"].size(), 3u);
}

// The closed box [lo, hi] as six quads, outward.
Mesh box(const V& lo, const V& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(V(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()));
  for (auto f : {std::array<std::uint32_t, 4>{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2},
                 {1, 3, 7, 5}})
    m.add_face_range(f);
  return m;
}

// Two meshes as one (their faces side by side, nothing welded).
Mesh joined(Mesh a, const Mesh& b) {
  const auto base = static_cast<std::uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (std::size_t f = 0; f < b.num_faces(); ++f) {
    std::vector<std::uint32_t> c;
    for (std::size_t k = 0; k < b.face_size(f); ++k) c.push_back(b.face(f)[k] + base);
    a.add_face_range(c);
  }
  return a;
}

TEST(SetupPrograms, TheCloudsPointsTheMeshDoesNotHoldAreKeptOffToo) {
  // The block's mesh lost a bump its cloud shows: a point 0.4 above the top's middle (a fold or a
  // filled hole of a reconstruction). Given the cloud, every feed move keeps the ball r - e/4 off
  // it, and the clearance plane clears it; without, the balls run through it.
  const Block b;
  const V bump(10, 5, 5.4);
  std::vector<V> cloud{bump};
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 10; ++j) cloud.push_back(V(i, j, 5));  // points the top face holds
  const double r = 2, e = 0.01;
  auto nearest_to_bump = [&](const std::vector<SetupProgram>& programs) {
    double least = INFINITY;
    for (const test::Segment& m : feed_centres(programs, b.setups, r)) {
      const V d = m[1] - m[0];
      const double t = d.squaredNorm() > 0 ? std::clamp((bump - m[0]).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      least = std::min(least, (m[0] + t * d - bump).norm());
    }
    return least;
  };
  const auto kept = setup_programs(b.path, b.counts, b.setups, b.part, {}, {}, {}, nullptr, nullptr, cloud);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_GE(nearest_to_bump(kept), r - e / 4 - 1e-4);
  EXPECT_GT(kept[0].lifted, 0u);
  EXPECT_NEAR(kept[0].clearance_z, 5.4 + 5, 1e-9);  // the top setup: z up
  const auto through = setup_programs(b.path, b.counts, b.setups, b.part, {}, {});
  EXPECT_LT(nearest_to_bump(through), r - 0.3);
  // Points the closed mesh holds (on its top, inside it) change nothing: the same programs.
  std::vector<V> held(cloud.begin() + 1, cloud.end());
  held.push_back(V(10, 5, 2.5));
  const auto same = setup_programs(b.path, b.counts, b.setups, b.part, {}, {}, {}, nullptr, nullptr, held);
  ASSERT_EQ(same.size(), through.size());
  for (std::size_t i = 0; i < same.size(); ++i) EXPECT_EQ(same[i].gcode, through[i].gcode);
}

// The square [0, side]^2 at height z as one flat patch, planned as contours (r, h = 0.05,
// e = 0.01), and the one clamping that cuts it from +z in the part's own frame.
Toolpath planned_square(double side, double z, double r) {
  ContourGridOptions o;
  o.tool_radius = r, o.scallop_height = 0.05, o.chord_error = 0.01;
  const SurfacePatch square = test::flat_patch({0, 0, z}, {side, 0, z}, {0, side, z}, {side, side, z}, {0, 0, 1});
  Toolpath path;
  path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = 0.01;
  path.passes = plan_contour_grid(BSplinePatch(square.surface, square.direction), o).passes;
  return path;
}

scallop::Setup plus_z() {
  scallop::Setup top;  // gtest has a Setup of its own
  top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
  return top;
}

TEST(SetupPrograms, ABallAgainstAWallIsLiftedOverIt) {
  // A 10 x 10 floor (z = 0) against a wall 5 mm high at x = 10: the contour along the floor's
  // edge x = 10 would put the ball (r = 2) into the wall; kept off, it rides on the wall's top
  // edge: its centre at z = 5 + 2 there, a lift of 5.
  const Mesh part = joined(box({0, 0, -5}, {10, 10, 0}), box({10, 0, -5}, {15, 10, 5}));
  const Toolpath path = planned_square(10, 0, 2);
  const auto programs = setup_programs(path, {path.passes.size()}, {plus_z()}, part, {}, {});
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_GT(programs[0].lifted, 0u);
  EXPECT_NEAR(programs[0].lift_max, 5.0, 0.01);
  // Those lifted more than r = 2 are counted: the highest (5) planned on the floor's edge x = 10.
  EXPECT_GT(programs[0].high_lifts, 0u);
  EXPECT_NEAR(programs[0].high_lift_max, 5.0, 0.01);
  EXPECT_NEAR(programs[0].high_lift_at.x(), 10, 0.01);
  EXPECT_NEAR(programs[0].high_lift_at.z(), 0, 1e-9);
  // No ball centre comes nearer than r - e/4 to the wall.
  const MeshDistance distance(part);
  for (const V& t : tips(programs[0].gcode)) EXPECT_GE(distance(t + V(0, 0, 2)), 2 - 0.0025 - 1e-4);
}

// The rapids keep lead_height off the whole part: beside the wall of ABallAgainstAWallIsLiftedOverIt
// a way down stops over the wall, not lead_height over the floor, and every rapid's ball ends at
// least r + lead_height from the part (2.5 mm here, for more stock than the default 1 mm).
TEST(SetupPrograms, TheRapidsKeepTheLeadHeightOffThePart) {
  const Mesh part = joined(box({0, 0, -5}, {10, 10, 0}), box({10, 0, -5}, {15, 10, 5}));
  const Toolpath path = planned_square(10, 0, 2);
  LinkOptions link;
  link.lead_height = 2.5;
  const auto programs = setup_programs(path, {path.passes.size()}, {plus_z()}, part, link, {});
  ASSERT_EQ(programs.size(), 1u);
  const MeshDistance distance(part);
  const auto& moves = programs[0].linked.moves;
  std::size_t ways_down = 0;
  for (std::size_t i = 1; i < moves.size(); ++i) {
    if (moves[i].kind != MoveKind::Rapid) continue;
    EXPECT_GE(distance(moves[i].tip + V(0, 0, 2)), 2 + 2.5 - 1e-3) << "rapid " << i << " to " << moves[i].tip.transpose();
    if (i + 1 < moves.size() && moves[i + 1].kind == MoveKind::Plunge) {
      ++ways_down;
      EXPECT_GE(moves[i].tip.z() - moves[i + 1].tip.z(), 2.5 - 1e-4);
    }
  }
  EXPECT_GE(ways_down, 1u);
}

TEST(SetupPrograms, BallsAreKeptTheMarginFartherFromWhereTheMeshCrossesItself) {
  // The cube [0, 4]^3 with the middle of its top pulled through its bottom, its top planned as a
  // flat patch (r = 1): with the tangle's keep-out, every ball centre stays r + margin - e/4 from
  // its samples (the part may be anywhere within half the margin of those faces); without, the
  // balls ride on the top, within that of them.
  std::set<std::size_t> spike;
  const Mesh part = test::spiked_cube(spike);
  const TangleKeepOut keep = tangle_keep_out(part, self_crossings(part));
  ASSERT_GT(keep.margin, 0);
  const Toolpath path = planned_square(4, 4, 1);
  const MeshDistance samples = MeshDistance(Mesh()).with_points(keep.samples);
  const auto kept = setup_programs(path, {path.passes.size()}, {plus_z()}, part, {}, {}, {}, nullptr, nullptr, {}, {}, keep);
  ASSERT_EQ(kept.size(), 1u);
  const std::vector<V> t = tips(kept[0].gcode);
  ASSERT_FALSE(t.empty());
  for (const V& tip : t) EXPECT_GE(samples(tip + V(0, 0, 1)), 1 + keep.margin - 0.0025 - 1e-4) << tip.transpose();
  const auto plain = setup_programs(path, {path.passes.size()}, {plus_z()}, part, {}, {});
  ASSERT_EQ(plain.size(), 1u);
  double nearest = INFINITY;
  for (const V& tip : tips(plain[0].gcode)) nearest = std::min(nearest, samples(tip + V(0, 0, 1)));
  EXPECT_LT(nearest, 1 + 0.5 * keep.margin);
}

TEST(SetupPrograms, APassEndUnderAnOverhangIsRaisedUntilTheBallGoesUpClear) {
  // A floor (z <= 0) and a block overhanging beside it ([12, 20] x [0, 10] x [10, 11]). A pass at
  // x = 10 on the floor: its balls (r = 3) are clear there and nothing lies straight above their
  // centres, but a ball going up to the clearance plane passes 2 mm from the block's side. Its
  // ends are raised to the lowest height whose vertical clears the block's top edge by
  // r - e/4: 11 + sqrt((3 - 0.0025)^2 - 2^2) = 13.2327 for the centre.
  const Mesh part = joined(box({0, 0, -5}, {10, 10, 0}), box({12, 0, 10}, {20, 10, 11}));
  Toolpath path;
  path.tool_radius = 3, path.scallop_height = 0.05, path.chord_error = 0.01;
  ToolpathPass pass;
  pass.contact = {V(10, 4, 0), V(10, 6, 0)};
  pass.normal = {V::UnitZ(), V::UnitZ()};
  path.passes = {pass};
  scallop::Setup top;
  top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
  const auto programs = setup_programs(path, {1}, {top}, part, {}, {});
  ASSERT_EQ(programs.size(), 1u);
  const double centre_z = 11 + std::sqrt(2.9975 * 2.9975 - 4);
  EXPECT_NEAR(programs[0].lift_max, centre_z - 3, 1e-8);
  // Every move of the program, rapids and plunges included, keeps the ball r - e/4 off the part.
  const std::vector<V> t = tips(programs[0].gcode);
  ASSERT_GE(t.size(), 3u);
  const std::vector<double> clearance = move_clearances(t, part, 3);
  for (std::size_t k = 1; k < t.size(); ++k)
    EXPECT_GE(clearance[k], 3 - 0.0025 - 2e-4) << "move " << k << " to " << t[k].transpose();
}

TEST(SetupPrograms, ABoxInFiveClampingsHasEveryFaceButItsBaseCutWithinH) {
  // The box [0, 40] x [0, 30] x [0, 12] on its base: top and four sides, a patch each; five
  // setups, five programs. Their ball centres, read back from the G-code and taken to the part
  // frame (p = R^T (q - t)), leave at most h on a grid of every face (sphere tracing along the
  // face's normal against the feed moves of all programs).
  const double X = 40, Y = 30, Z = 12, r = 2, h = 0.05;
  const Surfaces s = box_patches(X, Y, Z);
  const Mesh part = box({0, 0, 0}, {X, Y, Z});
  Toolpath path;
  std::vector<std::size_t> counts;
  plan_patches(s, r, h, s.patches.size(), path, counts);
  const auto setups = plan_setups(s, part);
  ASSERT_EQ(setups.size(), 5u);
  const auto programs = setup_programs(path, counts, setups, part, {}, {});
  ASSERT_EQ(programs.size(), 5u);
  EXPECT_LE(worst_scallop(s, feed_centres(programs, setups, r), r), h * 1.01);
}

TEST(SetupPrograms, FacesThePassesMissAreCutByRestPasses) {
  // The box above with passes on its top and two of its sides only: the rest passes cut the
  // other two sides from their own clampings (which have no pass of their own), within h.
  const double X = 40, Y = 30, Z = 12, r = 2, h = 0.05;
  const Surfaces s = box_patches(X, Y, Z);
  const Mesh part = box({0, 0, 0}, {X, Y, Z});
  Toolpath path;
  std::vector<std::size_t> counts;
  plan_patches(s, r, h, 3, path, counts);
  const auto setups = plan_setups(s, part);
  ASSERT_EQ(setups.size(), 5u);
  const auto without = setup_programs(path, counts, setups, part, {}, {});
  EXPECT_EQ(without.size(), 3u);
  EXPECT_GT(worst_scallop(s, feed_centres(without, setups, r), r), 1.0);  // two sides uncut

  RestOptions rest;
  rest.base_normal = {0, 0, -1};
  RestResult found;
  // Progress from 0 to 1, never back, through each phase.
  std::vector<std::pair<double, std::string>> told;
  const auto programs = setup_programs(path, counts, setups, part, {}, {}, {}, &rest, &found, {},
                                       [&](double f, const std::string& what) { told.emplace_back(f, what); });
  ASSERT_EQ(programs.size(), 5u);
  ASSERT_FALSE(told.empty());
  EXPECT_EQ(told.front(), std::make_pair(0.0, std::string("keeping setup 1 of 5 off the part")));
  EXPECT_EQ(told.back(), std::make_pair(1.0, std::string("programs written")));
  for (std::size_t i = 1; i < told.size(); ++i) EXPECT_GE(told[i].first, told[i - 1].first) << told[i].second;
  for (const char* phase : {"rest round 1, setup 1 of 5", "linking the passes of 5 setups"})
    EXPECT_TRUE(std::any_of(told.begin(), told.end(), [&](const auto& t) { return t.second == phase; })) << phase;
  EXPECT_EQ(found.new_setups, 0u);
  EXPECT_NEAR(found.measured_area, X * Y + 2 * (X + Y) * Z, 1e-6);
  EXPECT_GT(found.left_area_before, 2 * X * Z * 0.9);  // the two sides at least
  EXPECT_EQ(found.left_area_after, 0);
  for (const auto& p : programs) {
    if (setups[p.setup].patches.front() >= 3) {
      EXPECT_GT(p.rest_passes, 0u) << p.name;
    }
  }
  EXPECT_LE(worst_scallop(s, feed_centres(programs, setups, r), r), h * 1.01);
}

TEST(SetupPrograms, AMoveDownASlopeThatLacksALittleIsRaisedALittle) {
  // A cylinder of radius 20 along x (2880 facets around) and a pass down its side from 30 to 60
  // degrees off the top, balls (r = 2) every `step` radians planned `inside` mm into it (within
  // r - e/4, so not lifted): the moves between them dip toward it by their sagitta, and some are
  // found lacking by a hair of r - e/4. Such a move is raised by about what it lacks, not its
  // lower end to its upper end's height (before: lifts up to 0.155 mm here; on the domed block a
  // ball went up 0.129 mm for a move lacking 0.00007 mm, and left a 0.058 mm scallop).
  const double R = 20, r = 2, e = 0.01;
  Mesh part;
  constexpr int kAround = 2880;
  for (int k = 0; k < kAround; ++k) {
    const double t = 2 * std::numbers::pi * k / kAround;
    for (double x : {-5.0, 5.0}) part.vertices.push_back(V(x, R * std::sin(t), R * std::cos(t)));
  }
  for (std::uint32_t k = 0; k < kAround; ++k) {
    const std::uint32_t a = 2 * k, b = 2 * ((k + 1) % kAround);
    part.add_face({a, b, b + 1, a + 1});
  }
  for (double inside : {0.002, 0.0024})
    for (double step : {0.03, 0.05, 0.07}) {
      Toolpath path;
      path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
      ToolpathPass pass;
      for (double t = std::numbers::pi / 6; t <= std::numbers::pi / 3; t += step) {
        pass.normal.push_back(V(0, std::sin(t), std::cos(t)));
        pass.contact.push_back((R - inside) * pass.normal.back());
      }
      path.passes = {pass};
      scallop::Setup top;
      top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
      const auto programs = setup_programs(path, {1}, {top}, part, {}, {});
      ASSERT_EQ(programs.size(), 1u);
      // A point of a chord that dips (R + r)(1 - cos(step / 2)) goes up along z, on a slope of
      // at most 60 degrees, by at most twice that plus what the ball started inside.
      const double sagitta = (R + r) * (1 - std::cos(step / 2));
      EXPECT_LT(programs[0].lift_max, 2 * (sagitta + inside) + 1e-3) << "inside " << inside << " step " << step;
      const std::vector<V> t = tips(programs[0].gcode);
      const std::vector<double> clearance = move_clearances(t, part, r);
      for (std::size_t k = 1; k < t.size(); ++k)
        EXPECT_GE(clearance[k], r - e / 4 - 2e-4) << "step " << step << " move " << k << " to " << t[k].transpose();
    }
}

TEST(SetupPrograms, MovesJustClearOfTheFloorAreLeftWhereTheyAre) {
  // A 40 x 40 floor (z = 0) and passes along x and diagonally whose ball centres run 3e-5 mm above
  // the floor r - e/4 (r = 2, e = 0.01): every move is clear, so nothing is lifted and no ball is
  // put in a move's middle. (Bounded from samples, as before MeshDistance::least_on_segment, each
  // 0.37 mm move read 3.7e-6 under the floor and got balls in its middle until the pieces were
  // short enough for the bound to clear them: 579 tips here for 195 balls; on the block's 200k
  // cloud 1.43 M moves where 1.22 M do.)
  const double r = 2, e = 0.01, above = 3e-5;
  const Mesh part = box({-20, -20, -5}, {20, 20, 0});
  Toolpath path;
  path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
  for (const V& d : {V(1, 0, 0), V(1, 1, 0).normalized(), V(0.3, -1, 0).normalized()}) {
    ToolpathPass pass;
    for (double s = -12; s <= 12; s += 0.37) {
      pass.contact.push_back(s * d + V(0, 0, -e / 4 + above));
      pass.normal.push_back(V::UnitZ());
    }
    path.passes.push_back(pass);
  }
  const auto programs = setup_programs(path, {path.passes.size()}, {plus_z()}, part, {}, {});
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_EQ(programs[0].lifted, 0u);
  EXPECT_EQ(programs[0].lift_max, 0);
  // Every tip on the floor at one height (to the G-code's 4 decimals), the others up in the clear,
  // and no ball put in the middle of a move: the planned balls only.
  const std::vector<V> t = tips(programs[0].gcode);
  double low = INFINITY;
  for (const V& tip : t) low = std::min(low, tip.z());
  std::size_t on_floor = 0, planned = 0;
  for (const V& tip : t)
    if (tip.z() < low + 1) {
      EXPECT_NEAR(tip.z(), low, 1e-4);
      ++on_floor;
    }
  for (const auto& pass : path.passes) planned += pass.contact.size();
  EXPECT_EQ(on_floor, planned);
}

TEST(SetupPrograms, EveryMoveOverRoughGroundKeepsTheBallOffThePart) {
  // Columns of random heights (0 to 6 mm, 1 mm square) on a 12 x 12 grid, 8 of them, and passes
  // laid on the ground below them (contact z = 0, normal +z) every 0.7 mm: every ball and every
  // move must be lifted over the columns, r - e/4 off them (a move whose ends were raised level
  // and still reached in kept 0.01 mm of the fandisk at r = 2, e = 0.005 before such moves went
  // up as a whole; these grounds did not reproduce that case, they hold the invariant).
  const double r = 2, e = 0.01;
  for (int seed = 1; seed <= 8; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> height(0, 6);
    Mesh part = box({-2, -2, -5}, {14, 14, 0});
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j) part = joined(part, box({double(i), double(j), -1}, {i + 1.0, j + 1.0, height(rng)}));
    Toolpath path;
    path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
    for (int line = 0; line < 6; ++line) {
      ToolpathPass pass;
      const double y = 1.3 + 2 * line + 0.37 * (line % 2);
      for (double x = -1; x <= 13; x += 0.7) {
        pass.contact.push_back(V(x, y + 0.3 * std::sin(x), 0));
        pass.normal.push_back(V::UnitZ());
      }
      path.passes.push_back(pass);
    }
    scallop::Setup top;
    top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
    const auto programs = setup_programs(path, {path.passes.size()}, {top}, part, {}, {});
    ASSERT_EQ(programs.size(), 1u);
    const std::vector<V> t = tips(programs[0].gcode);
    ASSERT_GT(t.size(), 100u);
    const std::vector<double> clearance = move_clearances(t, part, r);
    for (std::size_t k = 1; k < t.size(); ++k)
      EXPECT_GE(clearance[k], r - e / 4 - 2e-4) << "move " << k << " to " << t[k].transpose();
    // the balls do come close: the test sees the clearance at work
    EXPECT_LT(*std::min_element(clearance.begin(), clearance.end()), r);
  }
}

TEST(SetupPrograms, APassUnderARoofIsCutWhereNoMoveCanBeKeptOff) {
  // A floor (z <= 0) and a roof over half of it ([20, 40] x [-5, 15] x [5, 6]). A pass along
  // y = 5 on the floor, balls every 0.02 mm: those under the roof cannot be reached from above and
  // go over it; the moves climbing there come too near the roof's edge, and raising one end per
  // sweep climbs back 0.02 mm at a time, more balls than its sweeps (a fandisk clamping kept a
  // 39 mm vertical move through the part that way). Wherever no move can be kept off, the pass is
  // cut, so every move of the program, links included, keeps the ball r - e/4 off the part.
  const double r = 2, e = 0.01;
  const Mesh part = joined(box({0, -5, -5}, {40, 15, 0}), box({20, -5, 5}, {40, 15, 6}));
  Toolpath path;
  path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
  ToolpathPass pass;
  for (int k = 0; k <= 1500; ++k) {
    pass.contact.push_back(V(2 + 0.02 * k, 5, 0));
    pass.normal.push_back(V::UnitZ());
  }
  path.passes = {pass};
  scallop::Setup top;
  top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
  const auto programs = setup_programs(path, {1}, {top}, part, {}, {});
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_GE(programs[0].splits, 1u);
  const std::vector<V> t = tips(programs[0].gcode);
  ASSERT_GT(t.size(), 100u);
  const std::vector<double> clearance = move_clearances(t, part, r);
  for (std::size_t k = 1; k < t.size(); ++k)
    EXPECT_GE(clearance[k], r - e / 4 - 2e-4) << "move " << k << " to " << t[k].transpose();
  // The floor before the roof is still cut: balls down on it up to r - e/4 before the roof's edge
  // (where their vertical clears it), not beyond.
  double last_on_floor = 0;
  for (const V& p : t)
    if (std::abs(p.z()) < 1e-6) last_on_floor = std::max(last_on_floor, p.x());
  EXPECT_GT(last_on_floor, 17.0);
  EXPECT_LE(last_on_floor, 20 - (r - e / 4) + 1e-9);
}

// A setup none of whose balls is left after keeping them off the part gets no program, and the
// other setups theirs: linking nothing threw "the tool path has no points" and stopped an ABC
// plate's noisy cloud at its programs. (A pass without points stands for one whose every ball
// was left out.)
TEST(SetupPrograms, ASetupWithNothingLeftToCutGetsNoProgramTheOthersTheirs) {
  const double r = 2, e = 0.01;
  const Mesh part = box({-5, -5, -5}, {15, 15, 0});
  Toolpath path;
  path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
  ToolpathPass pass;
  for (int k = 0; k <= 10; ++k) pass.contact.push_back(V(k, 5, 0)), pass.normal.push_back(V::UnitZ());
  path.passes = {ToolpathPass{}, pass};
  scallop::Setup empty, top;
  empty.name = "1: nothing", empty.axis = V::UnitZ(), empty.rotation.setIdentity(), empty.translation.setZero();
  empty.patches = {0};
  top = empty;
  top.name = "2: +z", top.patches = {1};
  const auto programs = setup_programs(path, {1, 1}, {empty, top}, part, {}, {});
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_EQ(programs[0].name, "2: +z");
  EXPECT_EQ(programs[0].setup, 1u);
  EXPECT_EQ(programs[0].file, "setup_1.ngc");
  EXPECT_GE(tips(programs[0].gcode).size(), 11u);
}

TEST(SetupPrograms, ABallDroppedOntoASlopeLandsWhereItTouchesNeverNearer) {
  // A plane tilted theta about y through the origin, n = (sin theta, 0, cos theta): a ball of
  // radius r dropped from above (x0, 0) touches it at centre height (r - x0 sin theta) / cos theta,
  // found exactly (MeshDistance::touch_along). Before stop 62 each step, the distance less r,
  // closed 1 - cos theta of the gap: 85 steps to 1e-6 at 80 degrees, 188 at 85.
  const double r = 2, x0 = 1.5;
  for (double degrees : {0.0, 30.0, 60.0, 80.0, 85.0, 89.0}) {
    const double t = degrees * std::numbers::pi / 180;
    const V n(std::sin(t), 0, std::cos(t)), u(std::cos(t), 0, -std::sin(t)), w(0, 1, 0);
    Mesh plane;
    for (double a : {-100.0, 100.0})
      for (double b : {-100.0, 100.0}) plane.vertices.push_back(a * u + b * w);
    plane.add_face({0, 2, 3, 1});
    const MeshDistance part(plane);
    const double touch = (r - x0 * std::sin(t)) / std::cos(t);
    V c(x0, 0, touch + 40);
    const double drop = drop_onto(c, part, r, 1000);
    EXPECT_NEAR(c.z(), touch, 1e-9 / std::cos(t)) << degrees;
    EXPECT_NEAR(drop, 40, 1e-9 / std::cos(t)) << degrees;
    EXPECT_NEAR(part(c), r, 1e-9) << degrees;
    // Lowered at most max_drop; a ball already touching does not move.
    V short_of(x0, 0, touch + 40);
    EXPECT_EQ(drop_onto(short_of, part, r, 25), 25);
    EXPECT_EQ(short_of.z(), touch + 15);
    EXPECT_EQ(drop_onto(c, part, r, 1000), 0);
  }
  // Into a V groove of half-angle 45 degrees (faces z = |x|): the ball comes to rest on the face
  // under it, at z = |x| + r sqrt(2), never nearer than r to the other; over the middle on both.
  Mesh groove;
  for (double x : {-50.0, 0.0, 50.0})
    for (double y : {-50.0, 50.0}) groove.vertices.push_back(V(x, y, std::abs(x)));
  groove.add_face({0, 2, 3, 1});
  groove.add_face({2, 4, 5, 3});
  const MeshDistance part(groove);
  V c(0.7, 0, 30);
  drop_onto(c, part, r, 1000);
  EXPECT_NEAR(c.z(), r * std::sqrt(2.0) + 0.7, 1e-9);
  EXPECT_GE(part(c), r - 1e-9);
  V middle(0, 0, 30);
  drop_onto(middle, part, r, 1000);
  EXPECT_NEAR(middle.z(), r * std::sqrt(2.0), 1e-9);
  // A ridge (z = -|x|): over x = -0.3 the ball rests on its apex, sqrt(r^2 - 0.09) above it.
  Mesh ridge = groove;
  for (auto& v : ridge.vertices) v.z() = -v.z();
  const MeshDistance roof(ridge);
  V top(-0.3, 0, 30);
  drop_onto(top, roof, r, 1000);
  EXPECT_NEAR(top.z(), std::sqrt(r * r - 0.09), 1e-9);
  EXPECT_GE(roof(top), r - 1e-9);
  // A point the part holds, 0.5 aside of the ball's way and 3 above the ridge's apex, held with a
  // margin of 0.1: the ball stops on it, at 3 + sqrt(2.1^2 - 0.5^2).
  const MeshDistance held = roof.with_points({V(-0.3, 0.5, 3)}, 0.1);
  V over(-0.3, 0, 30);
  drop_onto(over, held, r, 1000);
  EXPECT_NEAR(over.z(), 3 + std::sqrt(2.1 * 2.1 - 0.25), 1e-9);
}

TEST(SetupPrograms, ABallAboveThePartIsLoweredOntoItByAtMostFiveTimesItsSurfacesDistance) {
  // A floor (z <= 0) and a pass planned on a surface 0.3 mm above it (a smooth patch over a
  // faceted STL's flat facets): told the patch lies up to 0.3 off the part, the balls come down
  // until they touch the floor (tips at z = 0); told 0.05, by 5 x 0.05 = 0.25 (tips at 0.05);
  // told nothing, they stay. Never nearer than r.
  const double r = 2, e = 0.01;
  const Mesh part = box({-5, -5, -5}, {15, 15, 0});
  Toolpath path;
  path.tool_radius = r, path.scallop_height = 0.05, path.chord_error = e;
  ToolpathPass pass;
  for (double x = 0; x <= 10; x += 0.5) pass.contact.push_back(V(x, 5, 0.3)), pass.normal.push_back(V::UnitZ());
  path.passes = {pass};
  scallop::Setup top;
  top.name = "1: +z", top.axis = V::UnitZ(), top.rotation.setIdentity(), top.translation.setZero(), top.patches = {0};
  for (const auto& [off, tip_z] : {std::pair{0.3, 0.0}, {0.05, 0.05}, {-1.0, 0.3}}) {
    const std::vector<double> off_part = off < 0 ? std::vector<double>{} : std::vector<double>{off};
    const auto programs = setup_programs(path, {1}, {top}, part, {}, {}, off_part);
    ASSERT_EQ(programs.size(), 1u);
    EXPECT_EQ(programs[0].lowered, off < 0 ? 0u : pass.contact.size());
    std::size_t on_path = 0;
    for (const V& t : tips(programs[0].gcode))
      if (std::abs(t.y() - 5) < 1e-9 && t.z() < 1) {
        EXPECT_NEAR(t.z(), tip_z, 1e-4) << "off " << off;  // 4 decimals in the program
        ++on_path;
      }
    EXPECT_EQ(on_path, pass.contact.size()) << "off " << off;
    const std::vector<double> clearance = move_clearances(tips(programs[0].gcode), part, r);
    EXPECT_GE(*std::min_element(clearance.begin(), clearance.end()), r - 1e-4) << "off " << off;
  }
}

TEST(SetupPrograms, BadInputIsNamed) {
  const Block b;
  EXPECT_EQ(test::error_of<std::invalid_argument>(
                [&] { setup_programs(b.path, {1, 2}, b.setups, b.part, {}, {}); }),
            "the patches' pass counts do not add up to the toolpath's " + std::to_string(b.path.passes.size()) +
                " passes");
}

}  // namespace
}  // namespace scallop
