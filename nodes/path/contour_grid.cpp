#include "nodes/path/contour_grid.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <stdexcept>

#include "nodes/geom/kd_tree.h"
#include "nodes/geom/segment.h"
#include "nodes/path/step_size.h"

namespace scallop {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// [u0, u1] x [v0, v1]; u0 == u1 or v0 == v1: a segment (or a point).
struct Rect {
  double u0, u1, v0, v1;
};

// The segments of a ball-centre polyline, indexed by their midpoints for the scallop's ray
// queries (on the heap: the tree reads the midpoints in place, and contours are moved).
struct SegmentIndex {
  std::vector<Eigen::Vector3d> mid;
  std::vector<double> half;  // half lengths
  double half_max = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double extent = 0;  // every midpoint lies within this of centre
  PointsAdaptor<Eigen::Vector3d> adaptor{mid};
  KdTree<Eigen::Vector3d, 3> tree{3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};

  explicit SegmentIndex(const std::vector<Eigen::Vector3d>& c) {
    for (std::size_t k = 0; k + 1 < c.size(); ++k) {
      mid.push_back((c[k] + c[k + 1]) / 2);
      half.push_back((c[k + 1] - c[k]).norm() / 2);
      half_max = std::max(half_max, half.back());
    }
    if (mid.empty()) return;
    Eigen::Vector3d lo = mid[0], hi = mid[0];
    for (const auto& m : mid) lo = lo.cwiseMin(m), hi = hi.cwiseMax(m);
    centre = (lo + hi) / 2;
    extent = (hi - lo).norm() / 2;
    tree.buildIndex();
  }
};

struct Contour {
  std::vector<Eigen::Vector2d> uv;
  std::vector<Eigen::Vector3d> p, n, c;  // contact, unit normal, ball centre
  std::unique_ptr<SegmentIndex> index;   // over c, once the contour is complete
};

// The segments of one contour whose midpoints lie within `radius` of `centre`, kept for the
// samples of a strip near it (within `margin`): one tree search for many samples.
struct Near {
  double margin = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = -kInf;  // nothing collected yet
  std::vector<std::uint32_t> segments;
  std::vector<double> d2;  // scratch: each segment's midpoint's squared distance from the sample
};

// Side s of a rectangle, walked counter-clockwise in (u, v): 0 bottom (v = v0), 1 right (u = u1),
// 2 top (v = v1), 3 left (u = u0). A side along u steps across in v, and the other way round.
std::array<Eigen::Vector2d, 2> side_ends(const Rect& r, int s) {
  switch (s) {
    case 0: return {Eigen::Vector2d(r.u0, r.v0), Eigen::Vector2d(r.u1, r.v0)};
    case 1: return {Eigen::Vector2d(r.u1, r.v0), Eigen::Vector2d(r.u1, r.v1)};
    case 2: return {Eigen::Vector2d(r.u1, r.v1), Eigen::Vector2d(r.u0, r.v1)};
    default: return {Eigen::Vector2d(r.u0, r.v1), Eigen::Vector2d(r.u0, r.v0)};
  }
}
bool along_u(int s) { return s % 2 == 0; }

class ContourPlanner {
 public:
  ContourPlanner(const ParametricSurface& f, const ContourGridOptions& o) : f_(f), o_(o), r_(o.tool_radius) {}

  double chord_max = 0;
  std::size_t unreachable = 0;  // side samples where the ball cannot reach the bottom of a concave section
  double concave_radius_min = kInf;  // the tightest such section's radius (mm): a smaller ball would

  Contour contour(const Rect& r) {
    Contour c;
    for (int s = 0; s < 4; ++s) {
      const auto [a, b] = side_ends(r, s);
      trace(a, b, c);
    }
    add(c, c.uv.front());  // closed
    c.index = std::make_unique<SegmentIndex>(c.c);
    return c;
  }

  // The step across side s into the rectangle (parameter units), the smallest over its samples.
  double side_step(const Rect& r, int s, double h) {
    const auto [a, b] = side_ends(r, s);
    double step = kInf;
    for (int j = 0; j < o_.side_samples; ++j) {
      const Eigen::Vector2d uv = a + (b - a) * (double(j) / (o_.side_samples - 1));
      const SurfaceDerivatives d = f_.derivatives(uv);
      const FundamentalForms ff = fundamental_forms(d.ru, d.rv, d.ruu, d.ruv, d.rvv, d.sample.normal);
      const double along = along_u(s) ? ff.E : ff.G, across = along_u(s) ? ff.G : ff.E;
      // Where the side shrinks to a point (a patch's border collapsed: r_u = 0 along it) it has no
      // direction, and the angle and the direction across it are 0 / 0: the step is taken
      // straight across (an ABC plate's patch got NaN contours there, and GMP ended the run).
      const bool collapsed = !(along > 1e-12 * across);
      const double theta =
          collapsed ? std::numbers::pi / 2 : std::acos(std::clamp(ff.F / std::sqrt(ff.E * ff.G), -1.0, 1.0));
      // Across the pass, on the surface: perpendicular to r_u (a side along u) or to r_v.
      const double kappa = along_u(s) ? normal_curvature(ff, collapsed ? 0 : -ff.F / ff.E, 1)
                                      : normal_curvature(ff, 1, collapsed ? 0 : -ff.F / ff.G);
      double interval = side_interval(h, r_, kappa);
      if (!std::isfinite(interval)) {
        ++unreachable;
        concave_radius_min = std::min(concave_radius_min, -1 / kappa);
        interval = side_interval(h, r_, 0);  // the check between contours decides
      }
      const double sample_step = side_step_corrected(interval, std::sqrt(across), theta);
      if (std::isfinite(sample_step)) step = std::min(step, sample_step);
    }
    if (!std::isfinite(step))
      throw std::invalid_argument("the surface has no width across side " + std::to_string(s) + " of the rectangle (" +
                                  std::to_string(r.u0) + ".." + std::to_string(r.u1) + ", " + std::to_string(r.v0) +
                                  ".." + std::to_string(r.v1) + "): its patch is degenerate there");
    return step;
  }

  // The largest scallop between contours ca (rectangle a) and cb (rectangle b, inside a) over the
  // strip between their sides s: sampled, then the worst places refined.
  double strip_scallop(const Rect& a, const Rect& b, int s, const Contour& ca, const Contour& cb) const {
    // (t along, f across) in [0, 1]^2 -> (u, v)
    auto at = [&](double t, double f) -> Eigen::Vector2d {
      t = std::clamp(t, 0.0, 1.0), f = std::clamp(f, 0.0, 1.0);
      if (s == 0) return {a.u0 + t * (a.u1 - a.u0), a.v0 + f * (b.v0 - a.v0)};
      if (s == 1) return {a.u1 + f * (b.u1 - a.u1), a.v0 + t * (a.v1 - a.v0)};
      if (s == 2) return {a.u0 + t * (a.u1 - a.u0), a.v1 + f * (b.v1 - a.v1)};
      return {a.u0 + f * (b.u0 - a.u0), a.v0 + t * (a.v1 - a.v0)};
    };
    // The strip's length along contour a and its narrowest width, in mm on the surface: the
    // samples are spaced by the width in both directions however unevenly (u, v) is stretched
    // (in parameter units a corner of a 60 x 15 mm patch was sampled 0.5 mm apart, and missed).
    double length = 0, width = kInf;
    Eigen::Vector3d previous = f_(at(0, 0)).position;
    for (int i = 0; i <= 32; ++i) {
      const Eigen::Vector3d outer = f_(at(i / 32.0, 0)).position;
      length += (outer - previous).norm();
      previous = outer;
      width = std::min(width, (f_(at(i / 32.0, 1)).position - outer).norm());
    }
    const int along = std::clamp(static_cast<int>(std::ceil(8 * length / std::max(width, 1e-12))) + 1,
                                 2 * o_.side_samples, 20000),
              across = 9;
    // Samples within about a strip's width of each other share their tree searches.
    Near near_a, near_b;
    near_a.margin = near_b.margin = width > 0.05 ? std::min(width, 2.0) : 0.05;  // NaN too
    auto scallop = [&](double t, double f) {
      const SurfaceSample x = f_(at(t, f));
      return scallop_at(x, cb, near_b, scallop_at(x, ca, near_a, kInf));
    };
    // The worst sample overall and within a strip's width of either end (where the inner contour
    // turns a corner, the scallop peaks at a point where three distance fields meet, and falls
    // off linearly around it: a sample a little off misses it, 0.0215 measured for h = 0.02).
    const double corner = std::min(0.5, 1.5 * width / std::max(length, 1e-12));
    struct Best {
      double h = -1, t = 0, f = 0;
    };
    std::array<Best, 3> best;  // overall, start corner, end corner
    for (int g = 0; g < along; ++g) {
      const double t = double(g) / (along - 1);
      for (int k = 1; k <= across; ++k) {
        const double f = double(k) / (across + 1);  // 0.1 .. 0.9
        const double h = scallop(t, f);
        for (int z = 0; z < 3; ++z)
          if ((z == 0 || (z == 1 && t <= corner) || (z == 2 && t >= 1 - corner)) && h > best[z].h) best[z] = {h, t, f};
      }
    }
    double worst = 0;
    for (int z = 0; z < 3; ++z) {
      Best x = best[z];
      // A corner's best that is the overall one climbs the same way.
      if (x.h < 0 || (z > 0 && x.t == best[0].t && x.f == best[0].f)) continue;
      // Pattern search on a 3 x 3 stencil, halving it 12 times.
      double dt = 1.0 / (along - 1), df = 1.0 / (across + 1);
      for (int it = 0; it < 12; ++it, dt /= 2, df /= 2)
        for (bool moved = true; moved;) {
          moved = false;
          for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j) {
              if (i == 0 && j == 0) continue;  // where it stands
              const double t = std::clamp(x.t + i * dt, 0.0, 1.0), f = std::clamp(x.f + j * df, 0.0, 1.0);
              const double h = scallop(t, f);
              if (h > x.h + 1e-12) x = {h, t, f}, moved = true;
            }
        }
      worst = std::max(worst, x.h);
    }
    return worst;
  }

 private:
  const ParametricSurface& f_;
  const ContourGridOptions& o_;
  double r_;

  void add(Contour& c, const Eigen::Vector2d& uv) {
    if (!c.uv.empty() && c.uv.back() == uv) return;
    const SurfaceSample x = f_(uv);
    c.uv.push_back(uv);
    c.p.push_back(x.position);
    c.n.push_back(x.normal);
    c.c.push_back(x.position + r_ * x.normal);
  }

  Eigen::Vector3d centre(const Eigen::Vector2d& uv) const {
    const SurfaceSample x = f_(uv);
    return x.position + r_ * x.normal;
  }

  // Points of the straight (u, v) segment a -> b, a included, b not (the next side starts there).
  void trace(const Eigen::Vector2d& a, const Eigen::Vector2d& b, Contour& c) {
    const Eigen::Vector2d delta = b - a;
    add(c, a);
    if (delta.norm() == 0) return;
    for (double tau = 0; tau < 1;) {
      const SurfaceDerivatives d = f_.derivatives(a + tau * delta);
      const Eigen::Vector3d rt = d.ru * delta.x() + d.rv * delta.y();
      const Eigen::Vector3d rtt = d.ruu * delta.x() * delta.x() + 2 * d.ruv * delta.x() * delta.y() + d.rvv * delta.y() * delta.y();
      const double speed = rt.norm();
      double dtau = 1.0 / 64;
      if (speed > 0) {
        const double curvature = rt.cross(rtt).norm() / (speed * speed * speed);
        dtau = std::min(forward_interval(o_.chord_error, curvature), o_.max_segment) / speed;
      }
      dtau = std::min(dtau, 1 - tau);
      // The ball-centre chord against the ball-centre curve: at most e off it, and at most
      // part_clearance_tolerance(e) toward the surface (a convex pass's chords dip toward it).
      const Eigen::Vector3d c0 = d.sample.position + r_ * d.sample.normal;
      const double inward_limit = std::min(o_.chord_error, part_clearance_tolerance(o_.chord_error));
      for (int tries = 0; tries < 40; ++tries) {
        const Eigen::Vector3d c1 = centre(a + (tau + dtau) * delta);
        double dev = 0;
        bool dips = false;
        for (double q : {0.25, 0.5, 0.75}) {
          const SurfaceSample x = f_(a + (tau + q * dtau) * delta);
          const Eigen::Vector3d m = x.position + r_ * x.normal;
          const Eigen::Vector3d off = closest_on_segment(m, c0, c1) - m;
          dev = std::max(dev, off.norm());
          dips = dips || (off.dot(x.normal) < 0 && off.norm() > inward_limit);
        }
        if ((dev <= o_.chord_error && !dips) || tries == 39) {
          chord_max = std::max(chord_max, dev);
          break;
        }
        dtau /= 2;
      }
      tau = std::min(1.0, tau + dtau);
      if (tau < 1) add(c, a + tau * delta);
    }
  }

  // The least of `below` and the scallop at x left by the balls swept along contour c (+infinity
  // when they miss its normal). The ray cannot enter a capsule sooner than its distance from the
  // segment, less r, which is at least (distance to the midpoint) - (half length) - r: the segments
  // with midpoints within rho + r + the longest half length are looked at, rho growing until the
  // entry found is below it (then no farther segment can come first) or every segment was looked
  // at. The segments found within a wider ball around an earlier x (`near`, for x within its
  // margin) serve the samples nearby: a superset of those within reach, so the least entry is the
  // same. Segments that cannot come below `below` are not looked at.
  double scallop_at(const SurfaceSample& x, const Contour& c, Near& near, double below) const {
    const SegmentIndex& index = *c.index;
    double best = below;
    if (index.mid.empty()) return best;
    const double everything = (x.position - index.centre).norm() + index.extent;
    for (double rho = 2 * o_.scallop_height;; rho *= 4) {
      const double radius = rho + r_ + index.half_max;
      if (!((x.position - near.centre).norm() + radius <= near.radius)) {
        near.centre = x.position;
        near.radius = radius + near.margin;
        CollectWithin found{near.radius * near.radius, &near.segments};
        near.segments.clear();
        index.tree.findNeighbors(found, x.position.data(), nanoflann::SearchParams(32, 0, false));
      }
      // The segment with the nearest midpoint first (its entry is nearly always the least), then
      // only segments that could beat it: the entry into a capsule is at least the distance to its
      // segment less r, and that at least the distance to its midpoint less its half length.
      near.d2.resize(near.segments.size());
      std::uint32_t first = 0;
      double first_d2 = kInf;
      for (std::size_t i = 0; i < near.segments.size(); ++i) {
        const std::uint32_t k = near.segments[i];
        const double d2 = near.d2[i] = (index.mid[k] - x.position).squaredNorm();
        if (d2 < first_d2) first_d2 = d2, first = k;
      }
      if (first_d2 < kInf) best = std::min(best, ray_capsule_entry(x.position, x.normal, c.c[first], c.c[first + 1], r_));
      for (std::size_t i = 0; i < near.segments.size(); ++i) {
        const std::uint32_t k = near.segments[i];
        const double reach = best + index.half[k] + r_;  // +infinity while nothing was entered
        if (k == first || near.d2[i] >= reach * reach) continue;
        best = std::min(best, ray_capsule_entry(x.position, x.normal, c.c[k], c.c[k + 1], r_, best));
      }
      if (best <= rho || radius > everything) return best;
    }
  }
};

ToolpathPass to_pass(const Contour& c) {
  ToolpathPass p;
  p.contact = c.p;
  p.normal = c.n;
  p.uv = c.uv;
  return p;
}

}  // namespace

ContourGridResult plan_contour_grid(const ParametricSurface& surface, const ContourGridOptions& o) {
  if (!(o.tool_radius > 0)) throw std::invalid_argument("tool_radius must be positive");
  if (!(o.scallop_height > 0 && o.scallop_height < o.tool_radius))
    throw std::invalid_argument("scallop_height must lie between 0 and tool_radius");
  if (!(o.chord_error > 0)) throw std::invalid_argument("chord_error must be positive");
  if (!(o.max_segment > 0)) throw std::invalid_argument("max_segment must be positive");
  if (o.side_samples < 2) throw std::invalid_argument("side_samples must be at least 2");
  const UVDomain& domain = surface.domain();
  if (domain.kind != UVDomain::Kind::Rectangle || !(domain.width > 0 && domain.height > 0))
    throw std::invalid_argument("contour grids need a rectangle domain of positive size");

  ContourPlanner planner(surface, o);
  ContourGridResult result;
  Rect a{0, domain.width, 0, domain.height};
  Contour ca = planner.contour(a);
  result.passes.push_back(to_pass(ca));
  nlohmann::json lines = {{"u_from_0", {0.0}}, {"u_from_1", {domain.width}}, {"v_from_0", {0.0}}, {"v_from_1", {domain.height}}};
  double scallop_max = 0;
  std::array<double, 2> step_min{kInf, kInf}, step_max{0, 0};  // across u (sides 1, 3), across v (0, 2)
  std::size_t shrinks = 0, points = ca.uv.size();
  std::array<double, 4> share{1, 1, 1, 1};  // of each side's formula step to try first
  // A step grown or shrunk (scallop ~ step^2) aims at kAim^2 = 0.94 of h, not at h: aimed at 0.99
  // the block's contours were checked again after 3 829 shrinks, a check of four strips each, and
  // took 34.1 s; at 0.94, 906 shrinks and 25.8 s, for 1.8 % more contours.
  constexpr double kAim = 0.97;
  double limit_least = o.scallop_height;  // the least contour limit
  std::string warning;
  while (a.u1 > a.u0 && a.v1 > a.v0) {
    if (result.passes.size() >= o.max_contours)
      throw std::invalid_argument("more than max_contours (" + std::to_string(o.max_contours) +
                                  ") contours: the steps vanish near (u, v) = (" + std::to_string(a.u0) + ", " +
                                  std::to_string(a.v0) + ")");
    // Each side starts from its formula's step times the share the last contour's side kept, grown
    // by how far its scallop stayed under h: the corners, where three balls' fields meet, hold the
    // steps below the formula's (on a plane to about 0.85 of it) contour after contour.
    // The contour's limit: h less how far the surface lies off the part in the ring its sides'
    // formula steps at h may cross (a smaller limit only narrows the ring). One for all four
    // sides: a side held to h beside one held lower pushes the corner they share over it.
    std::array<double, 4> step, formula;
    for (int s = 0; s < 4; ++s) formula[s] = planner.side_step(a, s, o.scallop_height);
    double limit = o.scallop_height;
    if (o.scallop_limit) {
      const Rect ring{a.u0 + formula[3], a.u1 - formula[1], a.v0 + formula[0], a.v1 - formula[2]};
      limit = std::min({limit, o.scallop_limit(a.u0, a.u1, a.v0, std::max(ring.v0, a.v0)),
                        o.scallop_limit(a.u0, a.u1, std::min(ring.v1, a.v1), a.v1),
                        o.scallop_limit(a.u0, std::max(ring.u0, a.u0), a.v0, a.v1),
                        o.scallop_limit(std::min(ring.u1, a.u1), a.u1, a.v0, a.v1)});
      if (!(limit > 0)) throw std::invalid_argument("the scallop limit is not positive near (u, v) = (" +
                                                    std::to_string(a.u0) + ", " + std::to_string(a.v0) + ")");
      if (limit < o.scallop_height)
        for (int s = 0; s < 4; ++s) formula[s] = planner.side_step(a, s, limit);
    }
    limit_least = std::min(limit_least, limit);
    for (int s = 0; s < 4; ++s) step[s] = formula[s] * share[s];
    Rect b{};
    Contour cb;
    std::array<double, 4> worst{};
    for (int tries = 0;; ++tries) {
      b = {a.u0 + step[3], a.u1 - step[1], a.v0 + step[0], a.v1 - step[2]};
      // Sides that would cross meet at their middle, inside a.
      if (b.u0 >= b.u1) b.u0 = b.u1 = std::clamp((b.u0 + b.u1) / 2, a.u0, a.u1);
      if (b.v0 >= b.v1) b.v0 = b.v1 = std::clamp((b.v0 + b.v1) / 2, a.v0, a.v1);
      cb = planner.contour(b);
      bool ok = true;
      for (int s = 0; s < 4; ++s) {
        worst[s] = planner.strip_scallop(a, b, s, ca, cb);
        if (!(worst[s] <= limit)) {  // NaN too
          ok = false;
          step[s] *= std::max(0.1, kAim * std::sqrt(limit / worst[s]));  // scallop ~ step^2
          ++shrinks;
        }
      }
      if (ok) break;
      if (tries == 60) {
        warning = "the scallop between contours " + std::to_string(result.passes.size() - 1) + " and " +
                  std::to_string(result.passes.size()) + " stayed above h after 60 shrinks";
        break;
      }
    }
    for (int s = 0; s < 4; ++s) {
      scallop_max = std::max(scallop_max, worst[s]);
      // As a shrink does (scallop ~ step^2), at most doubling.
      const double grow = kAim * std::sqrt(limit / std::max(worst[s], limit / 4));
      share[s] = std::clamp(step[s] / formula[s] * grow, 0.01, 1.0);
      if (!std::isfinite(share[s])) share[s] = 1;
    }
    const std::array<double, 4> taken{b.v0 - a.v0, a.u1 - b.u1, a.v1 - b.v1, b.u0 - a.u0};
    for (int s = 0; s < 4; ++s)
      if (taken[s] > 0) {
        const int across_v = along_u(s) ? 1 : 0;
        step_min[across_v] = std::min(step_min[across_v], taken[s]);
        step_max[across_v] = std::max(step_max[across_v], taken[s]);
      }
    lines["u_from_0"].push_back(b.u0);
    lines["u_from_1"].push_back(b.u1);
    lines["v_from_0"].push_back(b.v0);
    lines["v_from_1"].push_back(b.v1);
    points += cb.uv.size();
    result.passes.push_back(to_pass(cb));
    a = b;
    ca = std::move(cb);
    if (o.progress)
      o.progress(1 - (a.u1 - a.u0) * (a.v1 - a.v0) / (domain.width * domain.height),
                 "contour " + std::to_string(result.passes.size()));
  }
  result.report = {{"contours", result.passes.size()},
                   {"points", points},
                   {"grid_lines", lines},
                   {"u_step_min", std::isfinite(step_min[0]) ? step_min[0] : 0.0},
                   {"u_step_max", step_max[0]},
                   {"v_step_min", std::isfinite(step_min[1]) ? step_min[1] : 0.0},
                   {"v_step_max", step_max[1]},
                   {"side_steps_shrunk", shrinks},
                   {"scallop_max", scallop_max},
                   {"scallop_limit_min", limit_least},
                   {"chord_max", planner.chord_max},
                   {"unreachable_samples", planner.unreachable}};
  if (planner.unreachable > 0) result.report["concave_radius_min"] = planner.concave_radius_min;
  if (!warning.empty()) result.report["warning"] = warning;
  return result;
}

}  // namespace scallop
