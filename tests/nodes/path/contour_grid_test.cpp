// Contour grids on exact surfaces written here (a plane, a convex ridge and a concave trough of
// radius 20 mm): the scallop measured over the whole patch by sphere tracing against the ball-
// centre polylines (not the planner's own ray-capsule test), the chord deviation against the
// exact ball-centre curve.
#include "nodes/path/contour_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "nodes/geom/bspline_surface.h"
#include "nodes/geom/point_text.h"
#include "nodes/path/step_size.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"
#include "nodes/types/surfaces.h"
#include "nodes/types/toolpath.h"
#include "tests/nodes/path/scallop_trace.h"
#include "tests/nodes/surface/surface_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace path_nodes {
NodeDecl make_contour_grid_node();
}  // namespace path_nodes

namespace {

using V = Eigen::Vector3d;

// u and v in mm along the surface. shape 0: the plane z = 0 over [0, 40] x [0, 30]; +1: a ridge
// (a cylinder of radius R about the y axis seen from outside), -1: a trough (seen from inside),
// u the arc length across 80 degrees, v along the axis over 30 mm.
struct Exact final : ParametricSurface {
  int shape;
  double R = 20;
  double sx = 1, sy = 1;  // the plane: (u, v) -> (x(u), y(v), 0), stretched unevenly unless 1
  double x(double u) const { return sx == 1 ? u : sx * (0.7 * u + 0.3 * u * u); }
  double y(double v) const { return sy == 1 ? v : sy * (0.8 * v + 0.2 * v * v * v); }
  UVDomain d;
  explicit Exact(int s) : shape(s) {
    d.kind = UVDomain::Kind::Rectangle;
    d.width = s == 0 ? 40 : R * 80 * M_PI / 180;
    d.height = 30;
  }
  SurfaceSample operator()(const Eigen::Vector2d& uv_in) const override {
    const Eigen::Vector2d uv = d.clamp(uv_in);
    SurfaceSample x;
    if (shape == 0) {
      x.position = V(this->x(uv.x()), y(uv.y()), 0);
      x.normal = V::UnitZ();
      return x;
    }
    const double a = (uv.x() - d.width / 2) / R;
    if (shape > 0) {
      x.position = V(R * std::sin(a), uv.y(), R * std::cos(a));
      x.normal = V(std::sin(a), 0, std::cos(a));
    } else {
      x.position = V(R * std::sin(a), uv.y(), -R * std::cos(a));
      x.normal = V(-std::sin(a), 0, std::cos(a));
    }
    return x;
  }
  const UVDomain& domain() const override { return d; }
  double uv_spacing() const override { return 0.01; }
};

using test::segment_distance;

// The largest scallop over an n x n grid of the whole domain (its rim included): the smallest t
// >= 0 with p + t n within r of a ball-centre polyline, by sphere tracing.
double measured_scallop(const Exact& s, const ContourGridResult& g, double r, int n) {
  std::vector<test::Segment> segs;
  for (const auto& p : g.passes)
    for (std::size_t k = 0; k + 1 < p.contact.size(); ++k)
      segs.push_back({p.contact[k] + r * p.normal[k], p.contact[k + 1] + r * p.normal[k + 1]});
  double worst = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const SurfaceSample x = s({s.d.width * i / (n - 1), s.d.height * j / (n - 1)});
      worst = std::max(worst, test::traced_scallop(x.position, x.normal, segs, r));
    }
  return worst;
}

// The largest distance from a segment's ball-centre chord to the exact centre at its middle.
double measured_chord(const Exact& s, const ContourGridResult& g, double r) {
  double worst = 0;
  for (const auto& p : g.passes)
    for (std::size_t k = 0; k + 1 < p.uv.size(); ++k) {
      const SurfaceSample m = s((p.uv[k] + p.uv[k + 1]) / 2);
      worst = std::max(worst, segment_distance(m.position + r * m.normal, p.contact[k] + r * p.normal[k],
                                               p.contact[k + 1] + r * p.normal[k + 1]));
    }
  return worst;
}

// The farthest a segment's ball-centre chord dips toward the surface from the exact centre at its
// middle (post.setup_programs lifts balls nearer the part than r - max(e/4, 0.001)).
double measured_dip(const Exact& s, const ContourGridResult& g, double r) {
  double worst = 0;
  for (const auto& p : g.passes)
    for (std::size_t k = 0; k + 1 < p.uv.size(); ++k) {
      const SurfaceSample m = s((p.uv[k] + p.uv[k + 1]) / 2);
      const V c = m.position + r * m.normal, a = p.contact[k] + r * p.normal[k], b = p.contact[k + 1] + r * p.normal[k + 1];
      const double t = std::clamp((c - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      worst = std::max(worst, -(a + t * (b - a) - c).dot(m.normal));
    }
  return worst;
}

ContourGridOptions options() {
  ContourGridOptions o;
  o.tool_radius = 3;
  o.scallop_height = 0.02;
  o.chord_error = 0.005;
  return o;
}

TEST(ContourGrid, APlaneGetsNestedRectanglesSpacedForTheirCorners) {
  const Exact plane(0);
  const ContourGridResult g = plan_contour_grid(plane, options());
  // Between two straight passes w apart the cusp is r - sqrt(r^2 - w^2/4): h = 0.02 at
  // w = 2 sqrt(2 r h - h^2) = 0.6917. Where the inner rectangle turns a corner, the point
  // farthest from the balls lies on the diagonal, at d = w sqrt(2) / (1 + sqrt(2)) = 0.586 w from
  // the two outer sides and the inner corner alike: h there needs d = sqrt(2 r h - h^2), so
  // w = 0.5904 (Algorithm 1, step 7: the corner shrinks the steps). The steps aim a little under
  // it, at 0.97 w (a scallop of 0.94 h: fewer checks shrink a step again).
  const double d = std::sqrt(2 * 3 * 0.02 - 0.02 * 0.02), w = d * (1 + std::sqrt(2.0)) / std::sqrt(2.0);
  const auto& lines = g.report["grid_lines"];
  for (const char* key : {"u_from_0", "v_from_0"}) {
    const double first = lines[key][1].get<double>() - lines[key][0].get<double>();
    EXPECT_LE(first, w + 1e-9) << key;
    EXPECT_GE(first, 0.96 * w) << key;
  }
  // Every contour's steps are the corner's, and after the first contour each side starts from the
  // share of the formula's step the last one kept: the checks shrink the first contour's sides
  // alone (the formula's 0.6917 is 1.17 w), not every contour's.
  const auto& u0 = lines["u_from_0"];
  for (std::size_t k = 1; k + 2 < u0.size(); ++k) {  // the last stops at the middle
    const double step = u0[k + 1].get<double>() - u0[k].get<double>();
    EXPECT_LE(step, w + 1e-9) << k;
    EXPECT_GE(step, 0.96 * w) << k;
  }
  EXPECT_LE(g.report["side_steps_shrunk"].get<int>(), 12);
  // 15 mm from the long sides to the middle.
  EXPECT_LE(g.passes.size(), std::size_t(std::ceil(15 / (0.96 * w))) + 1);
  EXPECT_GE(g.passes.size(), std::size_t(15 / w));
  EXPECT_LE(g.report["scallop_max"].get<double>(), 0.02);
  EXPECT_LE(measured_scallop(plane, g, 3, 61), 0.02 * 1.01);
  for (const auto& p : g.passes) EXPECT_EQ(p.uv.front(), p.uv.back());  // closed
  EXPECT_EQ(g.passes[0].uv[0], Eigen::Vector2d(0, 0));                 // the border first
}

// Where contour k + 1 turns a corner inside contour k, steps a and b from contour k's two sides
// there, the point farthest from the balls is d from both of contour k's sides and from contour
// k + 1's corner: (a - d)^2 + (b - d)^2 = d^2, d = a + b - sqrt(2 a b), when that point lies in the
// corner's square (d <= a, b); its scallop on a plane is r - sqrt(r^2 - d^2). The largest over
// every such corner, the steps in mm (the grid lines through x(u), y(v)).
template <class X, class Y>
double corner_scallop_max(const nlohmann::json& lines, double r, X x, Y y) {
  double worst = 0;
  const auto& u0 = lines["u_from_0"];
  const auto& u1 = lines["u_from_1"];
  const auto& v0 = lines["v_from_0"];
  const auto& v1 = lines["v_from_1"];
  for (std::size_t k = 0; k + 1 < u0.size(); ++k) {
    const double left = x(u0[k + 1].get<double>()) - x(u0[k].get<double>()),
                 right = x(u1[k].get<double>()) - x(u1[k + 1].get<double>());
    const double bottom = y(v0[k + 1].get<double>()) - y(v0[k].get<double>()),
                 top = y(v1[k].get<double>()) - y(v1[k + 1].get<double>());
    for (double a : {left, right})
      for (double b : {bottom, top}) {
        const double d = a + b - std::sqrt(2 * a * b);
        if (a > 0 && b > 0 && d <= std::min(a, b)) worst = std::max(worst, r - std::sqrt(r * r - d * d));
      }
  }
  return worst;
}

// A plane on the unit square stretched unevenly to 60 x 15 mm (as a B-spline patch of a block's
// side is): the strips are sampled by their size in mm, not in parameter units, or the corners
// where the steps differ are missed (0.053 for h = 0.05 was measured on such a patch).
TEST(ContourGrid, EveryCornerHoldsHOnAPlaneStretchedAsAPatchIs) {
  for (const auto& [sx, sy] : {std::pair{60.0, 15.0}, std::pair{15.0, 60.0}, std::pair{40.0, 30.0}}) {
    Exact plane(0);
    plane.d.width = plane.d.height = 1;
    plane.sx = sx, plane.sy = sy;
    ContourGridOptions o = options();
    o.scallop_height = 0.05;
    const ContourGridResult g = plan_contour_grid(plane, o);
    const double scallop = corner_scallop_max(
        g.report["grid_lines"], 3, [&](double u) { return plane.x(u); }, [&](double v) { return plane.y(v); });
    EXPECT_LE(scallop, 0.05 * (1 + 1e-6)) << sx << " x " << sy;
  }
}

TEST(ContourGrid, ARidgeAndATroughStayWithinHTheTroughWithWiderSteps) {
  std::map<int, double> first_u_step;
  for (int shape : {+1, -1}) {
    SCOPED_TRACE(shape);
    const Exact s(shape);
    const ContourGridResult g = plan_contour_grid(s, options());
    EXPECT_LE(g.report["scallop_max"].get<double>(), 0.02);
    EXPECT_LE(measured_scallop(s, g, 3, 61), 0.02 * 1.01);
    EXPECT_LE(measured_chord(s, g, 3), 0.005 * 1.01);
    EXPECT_LE(measured_dip(s, g, 3), 0.00125 * 1.01);  // max(e / 4, 0.001)
    if (shape > 0) {
      EXPECT_GT(measured_dip(s, g, 3), 0.0005);  // the ridge's chords do dip
    }
    const auto& u = g.report["grid_lines"]["u_from_0"];
    first_u_step[shape] = u[1].get<double>() - u[0].get<double>();
  }
  // Across the curvature Lin and Koren's interval is sqrt(8 h r R / (R +- r)): narrower over the
  // ridge, wider in the trough (the corners shrink both alike).
  EXPECT_LT(first_u_step[+1], first_u_step[-1]);
}

TEST(ContourGrid, ATroughTighterThanTheBallSaysWhatRadiusWouldFollowIt) {
  // A trough of radius 2.5 mm under a ball of 3: across it 1 + r kappa = 1 - 3 / 2.5 < 0, the ball
  // cannot reach its bottom. The report names the radius a smaller ball would follow; the
  // ridge of the same radius, convex, has none.
  Exact trough(-1), ridge(+1);
  for (Exact* s : {&trough, &ridge}) {
    s->R = 2.5;
    s->d.width = s->R * 80 * M_PI / 180;
  }
  const ContourGridResult t = plan_contour_grid(trough, options());
  EXPECT_GT(t.report["unreachable_samples"].get<std::size_t>(), 0u);
  EXPECT_NEAR(t.report["concave_radius_min"].get<double>(), 2.5, 1e-3);  // (curvature from differences)
  const ContourGridResult g = plan_contour_grid(ridge, options());
  EXPECT_EQ(g.report["unreachable_samples"].get<std::size_t>(), 0u);
  EXPECT_FALSE(g.report.contains("concave_radius_min"));
}

TEST(ContourGrid, TheNodeSaysWhichPatchCurvesTighterThanTheBallAndWhatWouldFollowIt) {
  // A parabolic trough z = (x - 1)^2 over x in [0, 2], y in [0, 10] (a quadratic Bezier across):
  // its bottom curves to a radius of 0.5 mm, under a ball of 2.
  auto s = std::make_shared<Surfaces>();
  SurfacePatch p;
  p.surface.degree_u = 2, p.surface.degree_v = 1;
  p.surface.knots_u = {0, 0, 0, 1, 1, 1}, p.surface.knots_v = {0, 0, 1, 1};
  p.surface.poles_u = 3, p.surface.poles_v = 2;
  p.surface.poles = {{0, 0, 1}, {1, 0, -1}, {2, 0, 1}, {0, 10, 1}, {1, 10, -1}, {2, 10, 1}};
  s->patches.push_back(p);
  std::vector<std::string> warnings;
  auto out = test::run_node(path_nodes::make_contour_grid_node(),
                            {{"tool_radius", 2}, {"scallop_height", 0.01}, {"chord_error", 0.005}}, {{"surfaces", s}},
                            nullptr, &warnings);
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data["patches"][0];
  const double radius = r["concave_radius_min"].get<double>();
  EXPECT_GE(radius, 0.5 - 1e-3);  // the parabola's least radius
  EXPECT_LT(radius, 0.75);        // where the samples come nearest its bottom
  const std::string prefix = "1 of 1 patches curve concave tighter than the tool (radius 2 mm) across their contours, "
                             "the tightest patch 0 to a radius of " + short_number(radius) + " mm, which a smaller ball "
                             "would follow (the report's concave_radius_min per patch)";
  EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                          [&](const std::string& w) { return w.rfind(prefix, 0) == 0; }),
            1);
}

TEST(ContourGrid, BadInputIsNamed) {
  const Exact plane(0);
  auto error = [&](ContourGridOptions o) {
    return test::error_of<std::invalid_argument>([&] { plan_contour_grid(plane, o); });
  };
  ContourGridOptions o = options();
  o.tool_radius = 0;
  EXPECT_EQ(error(o), "tool_radius must be positive");
  o = options();
  o.scallop_height = 3;
  EXPECT_EQ(error(o), "scallop_height must lie between 0 and tool_radius");
  o = options();
  o.max_contours = 3;
  EXPECT_EQ(error(o).substr(0, 35), "more than max_contours (3) contours");
}

// A patch whose side v = 0 shrinks to a point (a triangle, as the ABC plate's cloud gave one):
// along that side r_u = 0, the angle between r_u and r_v and the direction across are 0 / 0. The
// step there is taken straight across; before, it came out infinite, the next rectangle NaN, and
// CGAL's exact arithmetic ended the whole run (SIGFPE) when the programs measured those balls.
TEST(ContourGrid, APatchWithASideShrunkToAPointIsPlannedWithinH) {
  // The plane z = 0 over the triangle (0, 0), (-20, 30), (20, 30).
  const BSplinePatch patch(test::flat_patch(V(0, 0, 0), V(0, 0, 0), V(-20, 30, 0), V(20, 30, 0), V::UnitZ()).surface,
                           V::UnitZ());
  const ContourGridResult g = plan_contour_grid(patch, options());
  ASSERT_GE(g.passes.size(), 2u);
  std::vector<test::Segment> segs;
  for (const auto& p : g.passes)
    for (std::size_t k = 0; k < p.contact.size(); ++k) {
      ASSERT_TRUE(p.contact[k].allFinite() && p.normal[k].allFinite());
      if (k + 1 < p.contact.size())
        segs.push_back({p.contact[k] + 3 * p.normal[k], p.contact[k + 1] + 3 * p.normal[k + 1]});
    }
  EXPECT_LE(g.report["scallop_max"].get<double>(), 0.02);
  // Measured over the triangle, its rim included.
  double worst = 0;
  for (int i = 0; i <= 60; ++i)
    for (int j = 0; j <= i; ++j) {
      const double y = 30.0 * i / 60, x = i == 0 ? 0 : -y * 2 / 3 + (y * 4 / 3) * j / i;
      worst = std::max(worst, test::traced_scallop(V(x, y, 0), V::UnitZ(), segs, 3));
    }
  EXPECT_LE(worst, 0.02 * 1.01);
}

TEST(ContourGrid, TheNodePlansEveryPatchAlongItsOwnDirection) {
  // A 20 x 10 top (z = 5, up) and a 20 x 5 wall (y = 0, facing -y), bilinear patches.
  auto s = std::make_shared<Surfaces>();
  s->patches.push_back(test::flat_patch({0, 0, 5}, {20, 0, 5}, {0, 10, 5}, {20, 10, 5}, {0, 0, 1}));
  s->patches.push_back(test::flat_patch({0, 0, 0}, {20, 0, 0}, {0, 0, 5}, {20, 0, 5}, {0, -1, 0}));
  auto out = test::run_node(path_nodes::make_contour_grid_node(),
                            {{"tool_radius", 2}, {"scallop_height", 0.01}, {"chord_error", 0.005}}, {{"surfaces", s}});
  const auto& tp = *std::dynamic_pointer_cast<const Toolpath>(out.at("toolpath"));
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  ASSERT_EQ(r["patches"].size(), 2u);
  EXPECT_EQ(tp.passes.size(), r["contours"].get<std::size_t>());
  EXPECT_EQ(tp.pattern, "contour_grid");
  EXPECT_LE(r["scallop_max"].get<double>(), 0.01);
  const std::size_t top = r["patches"][0]["contours"].get<std::size_t>();
  for (std::size_t k = 0; k < tp.passes.size(); ++k)
    for (const V& n : tp.passes[k].normal) EXPECT_LT((n - (k < top ? V(0, 0, 1) : V(0, -1, 0))).norm(), 1e-12);
  EXPECT_EQ(test::error_of<NodeError>([] {
              test::run_node(path_nodes::make_contour_grid_node(), nlohmann::json::object(),
                             {{"surfaces", std::make_shared<Surfaces>()}});
            }),
            "path.contour_grid: there are no patches");
}

// The part's own mesh 0.004 mm under the patch: the scallop is held to h - 0.004 on the patch (a
// facet's sag on a curved part is like this), and never to less than h / 2. Patches more than
// h / 2 off are told in one line, however many they are.
TEST(ContourGrid, WhereThePartLiesOffThePatchTheLimitIsLoweredByThatMuch) {
  auto s = std::make_shared<Surfaces>();
  s->patches.push_back(test::flat_patch({0, 0, 5}, {20, 0, 5}, {0, 10, 5}, {20, 10, 5}, {0, 0, 1}));
  s->patches.back().rows = s->patches.back().cols = 2;
  s->patches.push_back(s->patches.back());
  for (const auto& [depth, target] : {std::pair{0.004, 0.006}, std::pair{1.0, 0.005}}) {
    auto part = std::make_shared<Mesh>();
    part->vertices = {{-5, -5, 5 - depth}, {25, -5, 5 - depth}, {25, 15, 5 - depth}, {-5, 15, 5 - depth}};
    part->add_face({0, 1, 2, 3});
    std::vector<std::string> warnings;
    auto out = test::run_node(path_nodes::make_contour_grid_node(),
                              {{"tool_radius", 2}, {"scallop_height", 0.01}, {"chord_error", 0.005}},
                              {{"surfaces", s}, {"part", part}}, nullptr, &warnings);
    if (depth > 0.005) {
      ASSERT_EQ(warnings.size(), 1u);
      EXPECT_EQ(warnings[0],
                "2 of 2 patches lie more than h / 2 off the part's faces (up to 1 mm, patch 0; the report's "
                "part_distance_max per patch): their contours there are planned to h / 2 and may leave more than h "
                "on the part (the certificate measures it)");
    } else {
      EXPECT_TRUE(warnings.empty());
    }
    const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data["patches"][0];
    EXPECT_NEAR(r["part_distance_max"].get<double>(), depth, 1e-9);
    EXPECT_NEAR(r["scallop_limit_min"].get<double>(), target, 1e-12);
    EXPECT_LE(r["scallop_max"].get<double>(), target);
    EXPECT_GT(r["scallop_max"].get<double>(), 0.9 * target);
  }
}

// The part 0.004 mm under a 20 x 20 mm patch only beyond x = 16 (a step in it, as a patch's rim
// over a rounded edge stands off the part): the outer contours, whose rings reach there, are
// held to h - 0.004; the inner ones, whose rings stay short of x = 15.5, to h. Measured on the
// contours themselves by sphere tracing: across the middle of the inner ones' sides (x = 10,
// 5.5 < y < 8.5; the steps are the corners', so mid-side the scallop is about 0.85^2 of the
// contour's aim, 0.0068 at h) over h - 0.004, beyond x = 17 under it.
TEST(ContourGrid, EachContourIsHeldToHLessThePartsDistanceInItsRing) {
  auto s = std::make_shared<Surfaces>();
  s->patches.push_back(test::flat_patch({0, 0, 5}, {20, 0, 5}, {0, 20, 5}, {20, 20, 5}, {0, 0, 1}));
  s->patches.back().rows = s->patches.back().cols = 11;  // the distances sampled every 0.5 mm
  auto part = std::make_shared<Mesh>();
  part->vertices = {{-5, -5, 5},     {16, -5, 5},     {16, 25, 5},     {-5, 25, 5},
                    {16, -5, 4.996}, {25, -5, 4.996}, {25, 25, 4.996}, {16, 25, 4.996}};
  part->add_face({0, 1, 2, 3});
  part->add_face({4, 5, 6, 7});
  auto out = test::run_node(path_nodes::make_contour_grid_node(),
                            {{"tool_radius", 2}, {"scallop_height", 0.01}, {"chord_error", 0.005}},
                            {{"surfaces", s}, {"part", part}});
  const auto& tp = *std::dynamic_pointer_cast<const Toolpath>(out.at("toolpath"));
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data["patches"][0];
  EXPECT_NEAR(r["part_distance_max"].get<double>(), 0.004, 1e-9);
  EXPECT_NEAR(r["scallop_limit_min"].get<double>(), 0.006, 1e-12);
  std::vector<test::Segment> segs;
  for (const auto& p : tp.passes)
    for (std::size_t k = 0; k + 1 < p.contact.size(); ++k)
      segs.push_back({p.contact[k] + 2 * p.normal[k], p.contact[k + 1] + 2 * p.normal[k + 1]});
  double inner = 0, right = 0;
  for (int i = 0; i <= 300; ++i) {
    const double y = 5.5 + 3.0 * i / 300;
    inner = std::max(inner, test::traced_scallop(V(10, y, 5), V::UnitZ(), segs, 2));
    for (double x : {17.2, 17.9, 18.6, 19.3}) right = std::max(right, test::traced_scallop(V(x, 8.5 + y - 5.5, 5), V::UnitZ(), segs, 2));
  }
  EXPECT_LE(inner, 0.01);
  EXPECT_GT(inner, 0.0063);
  EXPECT_LE(right, 0.006 * 1.001);
}

}  // namespace
}  // namespace scallop
