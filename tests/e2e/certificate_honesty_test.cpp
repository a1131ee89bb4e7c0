// The certificate must never pass a program that gouges or leaves too high a scallop on the real
// surface (issue 10). Sharp-curvature height fields written here (rounded crests and creases,
// rounded steps) are sampled into small clean and noisy clouds and planned by the shipped graph;
// each program is then measured by the product's own simulation (post.simulate's simulate_cut)
// against a dense exact cloud of the analytic surface, over the cloud's outline (its boundary
// loop, as the certificate's; nothing is promised beyond the outermost points). A passing
// certificate must mean that the exact surface holds the limits too: gouge <= e, scallop <=
// 1.01 h over the whole patch, rim included, nothing uncut. Cases where that does not hold yet (issue 10) are not
// here; each case below held on every seed tried.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/graph.h"
#include "engine/runner.h"
#include "nodes/all_nodes.h"
#include "nodes/geom/height_field_model.h"
#include "nodes/types/ply_writer.h"
#include "nodes/post/simulate.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

constexpr double kR = 4, kChord = 0.01;
// How far the exact measurement may exceed a limit and still pass: the simulation's sampling
// (the exact cloud's own fit error is added to it, see Outcome::fit_error).
constexpr double kTiny = 1e-4;

// A circular hole through the patch: no material within `radius` of (x, y).
struct Hole {
  double x, y, radius;
  bool contains(double px, double py) const { return std::hypot(px - x, py - y) < radius; }
};

// A height field over the patch [0, width] x [0, height] (mm), less its holes.
struct Surface {
  std::string name;
  std::function<double(double, double)> z;
  double width = 40, height = 30;
  std::vector<Hole> holes;
};

// Rounded crest running along y across the middle of the patch: flanks of slope a, radius c / a
// at its top (a hyperbola across it), z = z0 - a sqrt(s^2 + c^2).
Surface crest(double radius, double slope, double width = 40, double height = 30) {
  const double c = radius * slope, x0 = width / 2;
  return {"crest radius " + std::to_string(radius) + " slope " + std::to_string(slope),
          [=](double x, double) { return 10 - slope * std::hypot(x - x0, c); }, width, height, {}};
}
// Rounded crease: the crest upside down, concave with radius c / a at its bottom.
Surface crease(double radius, double slope, double width = 40, double height = 30) {
  const double c = radius * slope, x0 = width / 2;
  return {"crease radius " + std::to_string(radius) + " slope " + std::to_string(slope),
          [=](double x, double) { return 5 + slope * std::hypot(x - x0, c); }, width, height, {}};
}
// Rounded step of height `rise` running along y, a tanh ramp of half-width w (slope rise / 2w).
Surface step(double rise, double w, double width = 40, double height = 30) {
  const double x0 = width / 2;
  return {"step " + std::to_string(rise) + " over " + std::to_string(w),
          [=](double x, double) { return 5 + 0.5 * rise * std::tanh((x - x0) / w); }, width, height, {}};
}

// A gentle wave with two holes, 4 and 2.5 mm in radius, the larger 3.5 mm from the patch's edge.
Surface holed_wave() {
  return {"wave with two holes", [](double x, double y) { return 5 + 2 * std::sin(x / 8) * std::cos(y / 6); }, 40, 30,
          {{12, 15, 4}, {31, 9, 2.5}}};
}

// n points uniform over the patch on the surface (none in its holes), Gaussian noise sigma on x,
// y and z.
PointCloud sample(const Surface& s, int n, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0, s.width), uy(0, s.height);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    const double x = ux(rng), y = uy(rng);
    if (std::any_of(s.holes.begin(), s.holes.end(), [&](const Hole& h) { return h.contains(x, y); })) continue;
    Eigen::Vector3d p(x, y, s.z(x, y));
    if (sigma > 0) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    c.points.push_back(p);
  }
  return c;
}

// The exact surface as a clean 0.1 mm grid reaching 2 mm past the patch (so that fits at its
// edge are two-sided).
std::vector<Eigen::Vector3d> exact_grid(const Surface& s) {
  std::vector<Eigen::Vector3d> P;
  constexpr double d = 0.1;
  for (int i = -20; i <= static_cast<int>(std::lround(s.width / d)) + 20; ++i)
    for (int j = -20; j <= static_cast<int>(std::lround(s.height / d)) + 20; ++j)
      P.emplace_back(i * d, j * d, s.z(i * d, j * d));
  return P;
}

struct Case {
  Surface surface;
  double sigma = 0;   // noise (mm)
  int points = 5000;
  double h = 0.05;    // scallop limit (mm)
  int scales = 7;     // cloud.denoise's scales (its default)
  unsigned seed = 17;
  std::string graph = "isoparametric-zigzag";
};

struct Outcome {
  std::vector<std::string> errors;  // the graph's; empty when it produced a program
  nlohmann::json certificate;       // post.simulate's report on the denoised cloud
  nlohmann::json plan;              // path.isoparametric's report
  nlohmann::json exact;             // simulate_cut of the same program against the exact surface
  std::vector<double> uncertainty;  // the denoised cloud's
  std::vector<double> band;         // its height field's at its points (cloud.surface_band)
  double fit_error = 0;             // largest |z error| of the exact cloud's height field
  double seconds = 0;
  bool certified() const { return errors.empty() && certificate.value("pass", false); }
};

// Runs the shipped graph on a cloud of the case and measures its program on the exact surface.
Outcome run_case(const Case& c) {
  const auto t0 = std::chrono::steady_clock::now();
  const Surface& s = c.surface;
  test::TempDir dir;
  const auto ply = dir.path / "part.ply";
  write_ply(ply.string(), sample(s, c.points, c.sigma, c.seed));
  Graph g = load_graph(std::string(SCALLOP_SOURCE_DIR) + "/graphs/" + c.graph + ".json");
  // no pictures of the passes (time); the linked path is what the exact surface is cut with
  std::erase_if(g.nodes, [](const GraphNode& n) { return n.type == "post.render"; });
  std::erase_if(g.outputs, [&](const auto& o) {
    return std::none_of(g.nodes.begin(), g.nodes.end(),
                        [&](const GraphNode& n) { return o.second.rfind(n.id + ".", 0) == 0; });
  });
  g.outputs.emplace_back("linked", "link.linked");
  g.outputs.emplace_back("denoised", "denoise.cloud");
  g.outputs.emplace_back("loops", "loops.loops");
  g.outputs.emplace_back("band", "band.band");
  PartRequest req;
  req.inputs["cloud"] = ply.string();
  char h[32];
  std::snprintf(h, sizeof h, "%g", c.h);
  req.sets = {"tool_radius=4", "chord_error=0.01", std::string("scallop_height=") + h,
              "denoise.scales=" + std::to_string(c.scales)};
  req.part = "part";
  PartResult r = run_part(g, builtin_registry(), req);
  Outcome out;
  out.errors = r.errors;
  if (auto it = r.run.outputs.find("denoised"); it != r.run.outputs.end())
    out.uncertainty = std::static_pointer_cast<const PointCloud>(it->second)->uncertainty;
  if (auto it = r.run.outputs.find("band"); it != r.run.outputs.end())
    out.band = std::static_pointer_cast<const PointCloud>(it->second)->uncertainty;
  if (auto it = r.run.outputs.find("plan_report"); it != r.run.outputs.end())
    out.plan = std::static_pointer_cast<const Report>(it->second)->data;
  if (r.errors.empty()) {
    out.certificate = std::static_pointer_cast<const Report>(r.run.outputs.at("report"))->data;
    const auto linked = std::static_pointer_cast<const LinkedPath>(r.run.outputs.at("linked"));

    const HeightFieldModel exact(exact_grid(s), 20);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> ux(0, s.width), uy(0, s.height);
    for (int i = 0; i < 2000; ++i) {
      const double x = ux(rng), y = uy(rng);
      double z;
      Eigen::Vector3d n;
      out.fit_error = exact.eval(x, y, z, n) ? std::max(out.fit_error, std::abs(z - s.z(x, y))) : INFINITY;
    }
    double rapid = 0;
    const auto feed = feed_centres(*linked, rapid);
    SimulateOptions o;
    o.tool_radius = linked->tool_radius;
    o.scallop = linked->scallop_height;
    o.chord = linked->chord_error;
    // The cloud's outer loop, as the certificate's: beyond the outermost points nothing is known
    // and nothing promised. The holes' real edges: the part has material up to them, beyond the
    // cloud's loops around them.
    const auto denoised = std::static_pointer_cast<const PointCloud>(r.run.outputs.at("denoised"));
    const auto loops = std::static_pointer_cast<const BoundaryLoops>(r.run.outputs.at("loops"));
    for (const auto& loop : loops->loops) {
      o.loops.emplace_back();
      for (int i : loop) o.loops.back().push_back(denoised->points[i].head<2>());
      if (!s.holes.empty()) break;
    }
    for (const Hole& hole : s.holes) {
      o.loops.emplace_back();
      for (int k = 0; k < 720; ++k)
        o.loops.back().emplace_back(hole.x + hole.radius * std::cos(k * M_PI / 360), hole.y + hole.radius * std::sin(k * M_PI / 360));
    }
    out.exact = simulate_cut(exact, feed, rapid, o).report;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

// A report's number; NaN for null (e.g. no interior sample cut).
double num(const nlohmann::json& v) { return v.is_number() ? v.get<double>() : NAN; }

std::string describe(const Case& c) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s, %d points, noise %g, h %g, denoise.scales %d, seed %u, %s",
                c.surface.name.c_str(), c.points, c.sigma, c.h, c.scales, c.seed, c.graph.c_str());
  return buf;
}

std::string summary(const Outcome& o) {
  if (!o.errors.empty()) return "refused: " + o.errors.front();
  const auto& c = o.certificate;
  const auto& e = o.exact;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "certificate %s (scallop %.4f, interior %.4f, gouge %.4f); exact surface: scallop %.4f, interior "
                "%.4f, gouge %.4f, uncut %.3g (exact cloud's fit error %.1e; %.1f s)",
                c.value("pass", false) ? "pass" : "FAIL", num(c["scallop_max"]), num(c["scallop_max_interior"]),
                num(c["gouge_max"]), num(e["scallop_max"]), num(e["scallop_max_interior"]), num(e["gouge_max"]),
                num(e["uncut_fraction"]), o.fit_error, o.seconds);
  return buf;
}

// The reasons post.simulate gives for a failing certificate, rebuilt from its numbers (how each
// begins).
std::vector<std::string> expected_fail_reasons(const nlohmann::json& rep) {
  std::vector<std::string> reasons;
  char buf[160];
  if (rep["scallop_max"].is_null()) {
    reasons.push_back("no sample was cut");
  } else if (rep["scallop_max"].get<double>() > 1.01 * rep["scallop_limit"].get<double>()) {
    std::snprintf(buf, sizeof buf, "scallop max %.4g > 1.01 H (rim included; interior %.4g)",
                  rep["scallop_max"].get<double>(), num(rep["scallop_max_interior"]));
    reasons.push_back(buf);
  }
  const double gouge_tol = std::max(rep["chord_limit"].get<double>(), 0.001);
  if (rep["gouge_max"].get<double>() > gouge_tol) {
    std::snprintf(buf, sizeof buf, "gouge max %.4g > %.4g", rep["gouge_max"].get<double>(), gouge_tol);
    reasons.push_back(buf);
  }
  if (rep["uncut_fraction"].get<double>() > 0) {
    std::snprintf(buf, sizeof buf, "uncut fraction %.4g > 0", rep["uncut_fraction"].get<double>());
    reasons.push_back(buf);
  }
  return reasons;
}

// Runs the case and checks the certificate's promise against the exact surface.
Outcome expect_honest(const Case& c) {
  SCOPED_TRACE(describe(c));
  Outcome o = run_case(c);
  std::cout << "[ case     ] " << describe(c) << ": " << summary(o) << "\n";
  EXPECT_TRUE(o.errors.empty()) << o.errors.front();
  if (!o.errors.empty()) return o;
  EXPECT_LT(o.fit_error, 5e-4) << "the exact cloud's height field is not exact enough to measure with";
  const auto& cert = o.certificate;
  const auto& exact = o.exact;
  // (a bound's reason goes on to say where, and how much of it is the surface's uncertainty)
  const std::vector<std::string> reasons = cert["fail_reasons"], expected = expected_fail_reasons(cert);
  EXPECT_EQ(reasons.size(), expected.size());
  for (std::size_t i = 0; i < std::min(reasons.size(), expected.size()); ++i)
    EXPECT_EQ(reasons[i].substr(0, expected[i].size()), expected[i]);
  if (!cert["pass"].get<bool>()) return o;
  // the certificate passed: the real surface must hold the limits as well
  EXPECT_LE(exact["gouge_max"].get<double>(), kChord + kTiny + o.fit_error) << summary(o);
  EXPECT_LE(num(exact["scallop_max"]), 1.01 * c.h + o.fit_error) << summary(o);  // NaN: none cut
  EXPECT_EQ(exact["uncut_fraction"].get<double>(), 0.0) << summary(o);
  return o;
}

// ---- clean clouds, the default denoising --------------------------------------------

TEST(CertificateHonesty, CleanSharpCrests) {
  expect_honest({crest(0.5, 0.5)});
  expect_honest({crest(1, 0.3)});
}

// The exact surface holds the limits under a program planned on a 3 mm or 5 mm crest (h and e,
// rim included) since the height field takes a quartic where its quadratic misfits (stop 78):
// held off the crests by 3 times the quadratic's misfit, the stop-77 build's programs left a
// whole-patch scallop its certificate put at 0.322 and 0.194 mm.
// `scallop` names the exact surface's figure that must hold h: the whole patch's, or
// "scallop_max_interior" where only the interior is promised.
void expect_holds_on_the_exact_surface(const Outcome& o, double h, const char* scallop = "scallop_max") {
  ASSERT_TRUE(o.errors.empty());
  EXPECT_LE(num(o.exact[scallop]), 1.01 * h + o.fit_error) << summary(o);
  EXPECT_LE(o.exact["gouge_max"].get<double>(), kChord + kTiny + o.fit_error) << summary(o);
  EXPECT_EQ(o.exact["uncut_fraction"].get<double>(), 0.0) << summary(o);
}

// On the 3 mm crest the interior holds; where the crest runs out at the patch's edge the exact
// surface's whole-patch scallop exceeds h and the certificate, which fails there, says so. With
// the passes across the crest (the map's orientation before param.boundary_map v3) this sample
// of 5000 points held it too (0.0492), but another sample of the same surface did not in either
// orientation (0.0742 across, 0.0724 along; bench/extra_surfaces.py's verify, stop 83).
TEST(CertificateHonesty, CleanRoundedCrests) {
  expect_honest({crest(2, 0.7)});
  const Case three_mm{crest(3, 0.3)};
  const Outcome o = expect_honest(three_mm);
  ASSERT_TRUE(o.errors.empty());
  EXPECT_FALSE(o.certificate["pass"].get<bool>()) << summary(o);
  expect_holds_on_the_exact_surface(o, three_mm.h, "scallop_max_interior");
}

// The certificate's 20-point quadric lies about 0.001 mm low on this crest's top: before its
// misfit counted in the uncertainty, the certificate passed (gouge bound 0.0096) where the exact
// surface measured 0.0109.
TEST(CertificateHonesty, CleanWideCrestTheQuadricFlattens) {
  const Case five_mm{crest(5, 0.5)};
  expect_holds_on_the_exact_surface(expect_honest(five_mm), five_mm.h);
}

TEST(CertificateHonesty, CleanCreasesWiderThanTheBall) {
  expect_honest({crease(5, 0.5)});
  expect_honest({crease(8, 0.3)});
}

TEST(CertificateHonesty, CleanSteepRoundedStep) {
  expect_honest({step(3, 1.5)});
}

// A crease of radius 2 mm is tighter than the 4 mm ball: the planner says where it cannot reach
// and the certificate fails.
TEST(CertificateHonesty, CreaseTighterThanTheBallIsReportedAndNotCertified) {
  const Outcome o = expect_honest({crease(2, 0.5)});
  ASSERT_TRUE(o.errors.empty());
  EXPECT_FALSE(o.certificate["pass"].get<bool>());
  const auto& regions = o.plan["concave_regions"];
  double min_radius = INFINITY;  // of the regions on the crease (x = 20)
  for (const auto& r : regions["regions"])
    if (std::abs(r["centre"][0].get<double>() - 20.0) < 1.0)
      min_radius = std::min(min_radius, r["min_radius"].get<double>());
  EXPECT_NEAR(min_radius, 2.0, 0.2) << regions.dump();
  const std::string warning = std::to_string(regions["points"].get<int>()) +
                              " path points lie where the surface is concave with a radius below the tool radius: "
                              "the ball cannot reach there without gouging";
  const std::vector<std::string> warnings = o.plan["warnings"];
  EXPECT_NE(std::find(warnings.begin(), warnings.end(), warning), warnings.end()) << o.plan["warnings"].dump(1);
}

// A hole's edge lies beyond the cloud's points around it, as the outline does beyond its
// outermost ones: the band passes cut into the holes too. Without them (stop 89) both
// certificates passed while the exact surface, up to the holes' real edges, was left 0.0697 mm
// (zig-zag) and 0.0686 mm (contour) where the cloud stopped short of a hole's edge.
TEST(CertificateHonesty, CleanPatchWithHolesHoldsUpToTheHolesEdges) {
  for (const char* graph : {"isoparametric-zigzag", "isoparametric-contour"}) {
    Case c{holed_wave()};
    c.graph = graph;
    const Outcome o = expect_honest(c);
    ASSERT_TRUE(o.errors.empty());
    EXPECT_EQ(o.plan["outline_passes"].get<int>(), 3);  // the outer loop and both holes
    expect_holds_on_the_exact_surface(o, c.h);
  }
}

// The raster (param.planar: the points' own xy, the passes straight across it): its passes end
// on the outline at any angle, and the strips beside the rim pass are checked against its balls
// (path.isoparametric v22). Without that, where the strips were skipped within half a nominal
// interval of the outline, the catalog's clean dome kept 0.0543 mm at its rim (verify.py). On
// the wave with two holes the certificate passes and the exact surface holds over the whole
// patch; on the 2 mm crest, whose ends run out at the outline, the certificate fails (scallop
// bound 0.104 there) and the exact surface is over h there too (0.065): honest, not held.
TEST(CertificateHonesty, CleanRasterIsHonestAndHoldsOverTheWholeHoledPatch) {
  Case holed{holed_wave()};
  holed.graph = "raster-zigzag";
  const Outcome o = expect_honest(holed);
  ASSERT_TRUE(o.errors.empty());
  EXPECT_TRUE(o.certificate["pass"].get<bool>()) << summary(o);
  expect_holds_on_the_exact_surface(o, holed.h);
  Case crest_case{crest(2, 0.7)};
  crest_case.graph = "raster-zigzag";
  expect_honest(crest_case);
}

// ---- noisy clouds ------------------------------------------------------------------------------

// A wide noisy crease: the single-scale uncertainty suffices and the certificate passes (zig-zag
// and contour graphs).
TEST(CertificateHonesty, NoisyWideCreaseSingleScale) {
  expect_honest({crease(8, 0.3), 0.01, 4000, 0.1, 1});
}

TEST(CertificateHonesty, NoisyWideCreaseSingleScaleContour) {
  expect_honest({crease(8, 0.3), 0.01, 4000, 0.1, 1, 17, "isoparametric-contour"});
}

// A noisy rounded crest of radius 3 mm: one wide fit flattens it, and its single-scale
// uncertainty does not count that (issue 10); the multi-scale fits (denoise.scales = 7) do.
TEST(CertificateHonesty, NoisyCrestMultiScale) {
  expect_honest({crest(3, 0.3), 0.01, 4000, 0.1, 7});
}

// With more noise the multi-scale uncertainty is too large for h = 0.05: the planner refuses,
// saying how well the surface is known (the median of the denoised cloud's uncertainty). At
// sigma = 0.02 this 4000-point cloud's median, 0.0234 mm, is within 1 % of the limit (0.02325:
// h - delta - stock = 0.2 h, Margins); at 0.03 it is well over.
TEST(CertificateHonesty, NoisyCrestMultiScaleRefusesTooSmallAScallop) {
  const Case c{crest(3, 0.3), 0.03, 4000, 0.05, 7};
  SCOPED_TRACE(describe(c));
  const Outcome o = run_case(c);
  ASSERT_EQ(o.errors.size(), 1u) << summary(o);
  std::vector<double> u = o.uncertainty;
  ASSERT_FALSE(u.empty());
  ASSERT_EQ(o.band.size(), u.size());
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = std::min(u[i], o.band[i]);
  std::nth_element(u.begin(), u.begin() + u.size() / 2, u.end());
  char median[64];
  std::snprintf(median, sizeof median, "%g", u[u.size() / 2]);
  const std::string head = std::string("node 'plan' (path.isoparametric) failed on part 'part': the cloud's surface is "
                                        "known only to +-") +
                            median +
                            " mm (median; cloud.denoise's uncertainty or its height field's, the smaller), too much of "
                            "the scallop height 0.05 mm to promise it: denoise with more neighbours, scan more finely or "
                            "raise scallop_height (to at least ";
  // then the height the certificate's whole patch needs, where the crest runs out at the outline
  // and the field there is known worse than the points
  const std::string points = " mm for 99 % of the points; ", whole = " mm for a certificate of the whole patch, whose "
                                                                      "outline is known only to +-";
  const std::string tail = " mm) (given --set chord_error=0.01, --set scallop_height=0.05, --set tool_radius=4)";
  const std::string& e = o.errors[0];
  EXPECT_EQ(e.rfind(head, 0), 0u) << e;
  ASSERT_GT(e.size(), head.size() + tail.size()) << e;
  EXPECT_EQ(e.substr(e.size() - tail.size()), tail) << e;
  const double for_points = std::stod(e.substr(head.size()));
  EXPECT_GT(for_points, 0.05);  // the height it names is above the one given
  const std::size_t at_points = e.find(points, head.size()), at_whole = e.find(whole);
  ASSERT_NE(at_points, std::string::npos) << e;
  ASSERT_NE(at_whole, std::string::npos) << e;
  EXPECT_GT(std::stod(e.substr(at_points + points.size())), for_points) << e;
}

}  // namespace
}  // namespace scallop
