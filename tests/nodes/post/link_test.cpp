#include "nodes/post/link.h"

#include "nodes/geom/segment.h"
#include "nodes/path/gouge_guard.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scallop {
namespace {

// Zig-zag on the plane z = 0: passes along x at y = j s, alternating direction.
Toolpath zigzag(int passes, double s, double length = 10) {
  Toolpath t;
  t.tool_radius = 2;
  t.chord_error = 0.002;
  for (int j = 0; j < passes; ++j) {
    ToolpathPass p;
    for (int i = 0; i <= 10; ++i) {
      double x = (j % 2 ? 10 - i : i) * length / 10;
      p.contact.emplace_back(x, j * s, 0);
      p.normal.emplace_back(0, 0, 1);
    }
    t.passes.push_back(p);
  }
  return t;
}

// One pass along y from `start`, on a surface of normal n there (r = 2).
Toolpath pass_from(const Eigen::Vector3d& start, const Eigen::Vector3d& n) {
  Toolpath t;
  t.tool_radius = 2;
  t.chord_error = 0.002;
  ToolpathPass p;
  for (int i = 0; i <= 4; ++i) p.contact.push_back(start + Eigen::Vector3d(0, i, 0)), p.normal.push_back(n.normalized());
  t.passes.push_back(p);
  return t;
}

// The rapids keep lead_height off the part: they stop where a ball of r + lead_height coming down
// would touch it. On a plane sloped at 30 degrees that is lead_height / cos 30 above the start's
// tip; beside a wall 10 high, a ball touching its foot stops sqrt((r + lead)^2 - r^2) - r above
// the wall's top (the wall's edge within r + lead of the column), not 1 mm above the floor, where
// it would graze the wall.
TEST(Link, TheRapidsDownStopWhereABallOfRPlusTheLeadWouldTouchThePart) {
  const double r = 2, lead = 1, slope = M_PI / 6;
  std::vector<Eigen::Vector3d> plane;
  for (double x = -10; x <= 10; x += 0.02)
    for (double y = -6; y <= 10; y += 0.5) plane.emplace_back(x, y, x * std::tan(slope));
  const Eigen::Vector3d n(-std::sin(slope), 0, std::cos(slope));
  const Toolpath on_slope = pass_from(Eigen::Vector3d(0, 0, 0), n);
  const auto l = link_passes(on_slope, plane, {});
  ASSERT_GE(l.moves.size(), 3u);
  ASSERT_EQ(l.moves[1].kind, MoveKind::Rapid);
  ASSERT_EQ(l.moves[2].kind, MoveKind::Plunge);
  const Eigen::Vector3d tip = on_slope.tip(on_slope.passes[0].contact[0], on_slope.passes[0].normal[0]);
  EXPECT_NEAR(l.moves[1].tip.z() - tip.z(), lead / std::cos(slope), 1e-4);
  EXPECT_DOUBLE_EQ(l.moves[2].tip.z(), tip.z());
  // Up from the pass's end: fed to the same height over it, then the rapid.
  const auto& up = l.moves[l.moves.size() - 2];
  EXPECT_EQ(up.kind, MoveKind::Feed);
  EXPECT_NEAR(up.tip.z() - l.moves[l.moves.size() - 3].tip.z(), lead / std::cos(slope), 1e-4);

  std::vector<Eigen::Vector3d> floor_and_wall;
  for (int i = -200; i <= 300; ++i)  // x = i / 20: the wall's top edge a point at x = 5
    for (double y = -6; y <= 10; y += 0.5) floor_and_wall.emplace_back(i / 20.0, y, i < 100 ? 0 : 10);
  for (int k = 0; k <= 200; ++k)
    for (double y = -6; y <= 10; y += 0.5) floor_and_wall.emplace_back(5, y, k / 20.0);
  const auto w = link_passes(pass_from(Eigen::Vector3d(5 - r, 0, 0), Eigen::Vector3d(0, 0, 1)), floor_and_wall, {});
  ASSERT_EQ(w.moves[1].kind, MoveKind::Rapid);
  EXPECT_NEAR(w.moves[1].tip.z(), 10 + std::sqrt((r + lead) * (r + lead) - r * r) - r, 1e-9);
  // Away from the wall, 1 mm over the floor.
  const auto away = link_passes(pass_from(Eigen::Vector3d(-5, 0, 0), Eigen::Vector3d(0, 0, 1)), floor_and_wall, {});
  EXPECT_NEAR(away.moves[1].tip.z(), lead, 1e-9);
  // A whole part's drop, where given, decides in place of the points: a ball of r + lead coming
  // down from r above the clearance plane that stops after 3 mm.
  LinkOptions o;
  o.drop = [&](const Eigen::Vector3d& c, double radius, double) {
    EXPECT_DOUBLE_EQ(radius, r + lead);
    EXPECT_DOUBLE_EQ(c.z(), away.clearance_z + r);
    return 3.0;
  };
  const auto dropped = link_passes(pass_from(Eigen::Vector3d(-5, 0, 0), Eigen::Vector3d(0, 0, 1)), floor_and_wall, o);
  EXPECT_NEAR(dropped.moves[1].tip.z(), away.clearance_z - 3, 1e-9);
}

std::vector<Eigen::Vector3d> flat_cloud() {
  std::vector<Eigen::Vector3d> c;
  for (double x = -2; x <= 12; x += 0.25)
    for (double y = -2; y <= 6; y += 0.25) c.emplace_back(x, y, 0);
  return c;
}

int count(const LinkedPath& l, MoveKind k) {
  return static_cast<int>(std::count_if(l.moves.begin(), l.moves.end(), [&](const Move& m) { return m.kind == k; }));
}

TEST(Link, TheClearancePlaneIsAboveWhatTheTrimLeftOutToo) {
  // A wall 8 mm high beside the floor, not machined (cloud.trim_steep's left_out): the rapids at
  // the clearance plane would have crossed it 3 mm below its top.
  const auto floor = flat_cloud();
  std::vector<Eigen::Vector3d> wall;
  for (double z = 0.25; z <= 8 + 1e-9; z += 0.25)
    for (double y = -2; y <= 6; y += 0.25) wall.emplace_back(12.25, y, z);
  HeightFieldModel surface(floor);
  BallClearance without(surface, floor, 2.0), with(surface, floor, 2.0, nullptr, nullptr, 0, &wall);
  EXPECT_DOUBLE_EQ(link_passes(zigzag(4, 1.0), floor, {}, &without).clearance_z, 5.0);
  EXPECT_DOUBLE_EQ(link_passes(zigzag(4, 1.0), floor, {}, &with).clearance_z, 13.0);  // its top 8 + safety 5
}

TEST(Link, ShortSafeLinksAreFeedMoves) {
  auto l = link_passes(zigzag(4, 1.0), flat_cloud(), {});
  EXPECT_DOUBLE_EQ(l.clearance_z, 5.0);  // highest surface point 0 + safety 5
  // Rapid to clearance and down to lead height, plunge to the start; then all passes fed; lift
  // and rapid at the end.
  EXPECT_EQ(count(l, MoveKind::Rapid), 3);
  EXPECT_EQ(count(l, MoveKind::Plunge), 1);
  ASSERT_GE(l.moves.size(), 4u);
  EXPECT_EQ(l.moves[0].kind, MoveKind::Rapid);
  EXPECT_DOUBLE_EQ(l.moves[0].tip.z(), 5.0);
  EXPECT_EQ(l.moves[1].kind, MoveKind::Rapid);
  EXPECT_DOUBLE_EQ(l.moves[1].tip.z(), 1.0);  // lead height above the first tip
  EXPECT_EQ(l.moves[2].kind, MoveKind::Plunge);
  EXPECT_DOUBLE_EQ(l.moves[2].tip.z(), 0.0);
  EXPECT_EQ(l.moves.back().kind, MoveKind::Rapid);
  // 3 + 4 × 11 points + lift + rapid
  EXPECT_EQ(l.moves.size(), 3u + 4 * 10 + 3 + 2);
  // A lead reaching the clearance plane: straight from it at plunge rate.
  LinkOptions high;
  high.lead_height = 6;
  const auto h = link_passes(zigzag(4, 1.0), flat_cloud(), high);
  EXPECT_EQ(count(h, MoveKind::Rapid), 2);
  EXPECT_EQ(h.moves[1].kind, MoveKind::Plunge);
  EXPECT_DOUBLE_EQ(h.moves[1].tip.z(), 0.0);
}

// A link across a convex dome z = 10 - 0.005 (x^2 + y^2) sampled every 2 mm: the straight move of
// the ball centre from (-2, 1) to (2, 1) dips about 0.02 mm into the surface midway, between the
// cloud's points (the nearest lies 1 mm aside, where the ball is 0.16 mm higher). The points alone
// let it through; the cloud's height field, which the certificate measures against, does not.
TEST(Link, ALinkThatDipsBetweenSparsePointsIsCaughtByTheHeightField) {
  auto z = [](double x, double y) { return 10 - 0.005 * (x * x + y * y); };
  auto normal = [](double x, double y) { return Eigen::Vector3d(0.01 * x, 0.01 * y, 1).normalized(); };
  std::vector<Eigen::Vector3d> cloud;
  for (double x = -20; x <= 20; x += 2)
    for (double y = -20; y <= 20; y += 2) cloud.emplace_back(x, y, z(x, y));
  Toolpath t;
  t.tool_radius = 3;
  t.chord_error = 0.005;
  for (double x : {-2.0, 2.0}) {
    ToolpathPass p;
    p.contact.emplace_back(x, 1, z(x, 1));
    p.normal.push_back(normal(x, 1));
    t.passes.push_back(p);
  }
  const auto points_only = link_passes(t, cloud, {});
  EXPECT_EQ(count(points_only, MoveKind::Rapid), 3);  // over, down ... up: the link is a feed move
  const HeightFieldModel model(cloud, 20);
  const BallClearance clearance(model, cloud, t.tool_radius);
  const auto checked = link_passes(t, cloud, {}, &clearance);
  EXPECT_EQ(count(checked, MoveKind::Rapid), 6);  // over, down, up, over, down, up
}

// A link along a ridge of radius 3 (a cylinder's top, z = sqrt(9 - x^2)), its ball centres 6.95
// from the axis: 0.05 mm into the ridge all along, beside its top (x = 1.5). The points miss it
// (none lies within a strip 0.8 wide where the ball comes nearest); the height field across the
// strip does not. Found from below the centre by stepping to c - r n, the foot swung from side
// to side of the top (the step overshoots by r / R = 4 / 3) and never came near.
TEST(Link, ALinkBesideTheTopOfARidgeTighterThanTheBallIsCaught) {
  constexpr double R = 3, r = 4, D = 6.95, cx = 1.5;
  std::vector<Eigen::Vector3d> cloud;
  for (double y = -6; y <= 6 + 1e-9; y += 0.3) {
    for (double x = 0.25; x >= -2.9; x -= 0.3) cloud.emplace_back(x, y, std::sqrt(R * R - x * x));
    for (double x = 1.05; x <= 2.9; x += 0.3) cloud.emplace_back(x, y, std::sqrt(R * R - x * x));
  }
  Toolpath t;
  t.tool_radius = r;
  t.chord_error = 0.005;
  const Eigen::Vector3d n = Eigen::Vector3d(cx, 0, std::sqrt(D * D - cx * cx)) / D;
  for (double y : {-1.0, 1.0}) {
    ToolpathPass p;
    p.contact.push_back(Eigen::Vector3d(0, y, 0) + (D - r) * n);  // its centre D from the axis
    p.normal.push_back(n);
    t.passes.push_back(p);
  }
  for (const auto& q : cloud)  // no point within r - e of the link
    EXPECT_GT(segment_distance(q, t.centre(t.passes[0].contact[0], n), t.centre(t.passes[1].contact[0], n)), r - 0.005);
  EXPECT_EQ(count(link_passes(t, cloud, {}), MoveKind::Rapid), 3);  // the link a feed move
  const HeightFieldModel model(cloud, 20);
  const BallClearance clearance(model, cloud, r);
  EXPECT_EQ(count(link_passes(t, cloud, {}, &clearance), MoveKind::Rapid), 6);  // over, down, up, over, down, up
}

TEST(Link, LinksOverABumpOrTooLongRetract) {
  auto cloud = flat_cloud();
  cloud.emplace_back(10.0, 0.5, 0.5);  // a bump between the end of pass 0 and the start of pass 1
  auto l = link_passes(zigzag(2, 1.0), cloud, {});
  EXPECT_DOUBLE_EQ(l.clearance_z, 5.5);
  EXPECT_EQ(count(l, MoveKind::Rapid), 6);  // over, down, up, over, down, up
  EXPECT_EQ(count(l, MoveKind::Plunge), 2);
  for (std::size_t i = 0; i < l.moves.size(); ++i)
    if (l.moves[i].kind == MoveKind::Rapid && (i + 1 == l.moves.size() || l.moves[i + 1].kind != MoveKind::Plunge))
      EXPECT_DOUBLE_EQ(l.moves[i].tip.z(), 5.5);  // all at the clearance plane but the way down to the lead

  LinkOptions o;
  o.max_link = 0.5;  // shorter than the stepover
  auto l2 = link_passes(zigzag(3, 1.0), flat_cloud(), o);
  EXPECT_EQ(count(l2, MoveKind::Plunge), 3);
}

// With link_clear (a whole part's check, which holds the points) the link is its answer alone:
// the bump the points show is the check's to see, and a check that refuses the link refuses it
// over a flat cloud. The points still set the clearance plane.
TEST(Link, AWholePartsCheckDecidesTheLinksInPlaceOfThePoints) {
  auto cloud = flat_cloud();
  cloud.emplace_back(10.0, 0.5, 0.5);  // the bump of LinksOverABumpOrTooLongRetract
  LinkOptions o;
  int asked = 0;
  o.link_clear = [&](const Eigen::Vector3d&, const Eigen::Vector3d&) { return ++asked, true; };
  auto l = link_passes(zigzag(2, 1.0), cloud, o);
  EXPECT_EQ(asked, 1);
  EXPECT_EQ(count(l, MoveKind::Rapid), 3);  // fed across
  EXPECT_DOUBLE_EQ(l.clearance_z, 5.5);
  o.link_clear = [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return false; };
  EXPECT_EQ(count(link_passes(zigzag(2, 1.0), flat_cloud(), o), MoveKind::Rapid), 6);
}

TEST(Link, WithoutACloudThePassesStandForTheSurface) {
  auto l = link_passes(zigzag(3, 1.0), {}, {});
  EXPECT_EQ(count(l, MoveKind::Plunge), 1);
  EXPECT_DOUBLE_EQ(largest_stepover(zigzag(3, 1.5)), 1.5);
}

TEST(Link, PassesFarAboveThePartFailWithWhereAndWhy) {
  // r = 2, the flat part's height range 0: a pass point 20 mm up is allowed, 20.5 mm is not
  Toolpath t = zigzag(2, 1.0);
  t.passes[1].contact[3].z() = 20;
  EXPECT_DOUBLE_EQ(link_passes(t, flat_cloud(), {}).clearance_z, 25.0);
  t.passes[1].contact[3].z() = 20.5;
  try {
    link_passes(t, flat_cloud(), {});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "the passes rise to z 20.5 near x 7, y 1, 20.5 mm above the part's top (z 0): more than 10 tool "
                 "radii + the part's height range (20 mm), so the clearance plane would be at z 25.5; the passes do "
                 "not follow the surface there (e.g. a gouge guard lift at a fold-over of the (u,v) map)");
  }
  // without a cloud the passes are the surface: nothing to compare with
  EXPECT_DOUBLE_EQ(link_passes(t, {}, {}).clearance_z, 25.5);
}

TEST(Link, BadInputIsRefused) {
  Toolpath t = zigzag(2, 1.0);
  t.passes[1].normal.pop_back();
  try {
    link_passes(t, {}, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "a pass has 11 points but 10 normals");
  }
  Toolpath empty;
  empty.tool_radius = 1;
  try {
    link_passes(empty, {}, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the tool path has no points");
  }
}

// Two passes on the plane z = 0 (points every 0.25 mm over [-10, 10]^2, each known to +-0.02)
// joined by a link of the ball centre along x = x_link from y = -1 to 1, the ball `above` the
// plane.
struct UncertainPlaneLink {
  std::vector<Eigen::Vector3d> cloud;
  std::vector<double> uncertainty;
  Toolpath path;
  UncertainPlaneLink(double x_link, double above, double gap_radius = 0) {
    for (double x = -10; x <= 10 + 1e-9; x += 0.25)
      for (double y = -10; y <= 10 + 1e-9; y += 0.25)
        if (std::hypot(x - 10, y) > gap_radius) cloud.emplace_back(x, y, 0);
    uncertainty.assign(cloud.size(), 0.02);
    path.tool_radius = 2;
    path.chord_error = 0.005;
    for (double y : {-1.0, 1.0}) {
      ToolpathPass p;
      p.contact.emplace_back(x_link, y, above);
      p.normal.emplace_back(0, 0, 1);
      path.passes.push_back(p);
    }
  }
};

// The ball must clear the height field by its uncertainty less the tolerance, and less 0.15 of
// the uncertainty (the certificate samples it between the places checked, where it is rough):
// over the plane known to +-0.02 with e = 0.005, a link may reach 0.005 - 0.003 = 0.002 into the
// band. 0.0015 in: a feed link; 0.003 in (within e): refused.
TEST(Link, ALinkOverAnUncertainSurfaceKeepsTheGougeBudget) {
  for (const auto& [reach, rapids] : {std::pair{0.0015, 3}, std::pair{0.003, 6}}) {
    const UncertainPlaneLink at(0, 0.02 - reach);
    const HeightFieldModel model(at.cloud, 20, &at.uncertainty);
    const BallClearance clearance(model, at.cloud, at.path.tool_radius);
    EXPECT_EQ(count(link_passes(at.path, at.cloud, {}, &clearance), MoveKind::Rapid), rapids) << reach;
  }
}

// A gap at the rim: no points within 2 mm of (10, 0). A link along x = 9.5 over it, the ball
// 0.02 above the plane (it clears the points' band exactly), passes where the field is
// extrapolated and its uncertainty grown: off the patch for the model alone (the nearest point
// 1.5 mm away), so the link is let through; inside the patch's outline (the square), where the
// certificate measures, it is refused.
TEST(Link, ALinkOverAGapBetweenRimPointsIsCheckedInsideTheOutline) {
  const UncertainPlaneLink at(9.5, 0.02, 2.0);
  const HeightFieldModel model(at.cloud, 20, &at.uncertainty);
  double z, u;
  Eigen::Vector3d n;
  EXPECT_FALSE(model.eval(9.5, 0, z, n, false, &u));
  EXPECT_GT(u, 0.03);
  const BallClearance without(model, at.cloud, at.path.tool_radius);
  EXPECT_EQ(count(link_passes(at.path, at.cloud, {}, &without), MoveKind::Rapid), 3);
  const Outline square({{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}});
  const BallClearance inside(model, at.cloud, at.path.tool_radius, &square);
  EXPECT_EQ(count(link_passes(at.path, at.cloud, {}, &inside), MoveKind::Rapid), 6);
}

// In the same gap (no points within 1.2 mm of (10, 0)), a link along x = 9.6 whose ball clears
// the band at every foot point by 0.002 more than the uncertainty there (e = 0.005: a check at the
// foot alone lets it through, reach <= -0.002 < e - 0.15 u) reaches deeper a few tenths of a mm
// outward, where the field's uncertainty grows faster than the ball's distance from the plane.
// The certificate samples there; the link is checked as the gouge guard checks a ball, and
// refused (a zig-zag turn at the noisy bowl's rim, checked at its feet alone, reached 0.0115
// into the band).
TEST(Link, ALinkInAGapAtTheRimIsCheckedAroundItsFeet) {
  const UncertainPlaneLink probe(9.6, 0, 1.2);
  const HeightFieldModel model(probe.cloud, 20, &probe.uncertainty);
  double above = 0;  // the largest uncertainty along the link, + 0.002
  for (double y = -1; y <= 1 + 1e-9; y += 0.01) above = std::max(above, model.uncertainty(9.6, y) + 0.002);
  for (double y = -1; y <= 1 + 1e-9; y += 0.01) {
    const double u = model.uncertainty(9.6, y);
    EXPECT_LT(u - above, 0.005 - 0.15 * u) << y;  // the foot alone: clear
  }
  const UncertainPlaneLink at(9.6, above, 1.2);
  const Outline square({{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}});
  const BallClearance clearance(model, at.cloud, at.path.tool_radius, &square);
  EXPECT_EQ(count(link_passes(at.path, at.cloud, {}, &clearance), MoveKind::Rapid), 6);
}

}  // namespace
}  // namespace scallop
