#include "nodes/path/isoparametric.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_invoke.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "nodes/cloud/cloud_height_field.h"
#include "nodes/geom/height_field_model.h"
#include "nodes/geom/point_text.h"
#include "nodes/path/step_size.h"
#include "nodes/geom/outline.h"
#include "nodes/path/uv_interpolation.h"
#include "nodes/geom/kd_tree.h"

namespace scallop {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 2 * M_PI;
// A strip check's scallop where a place across the strip is reached by neither pass's ball (a
// ray from the surface misses both): uncut, not a height.
constexpr double kUncut = 1e9;
// Bounds on the work: beyond these the map or the cloud is broken (a degenerate map makes the
// steps vanish), and the planner stops with a clear error instead of running on for hours.
constexpr std::size_t kMaxPassPoints = 200000;

// (s, t) pass coordinates -> uv; see the header.
struct Coords {
  bool polar = false;
  double S = 0;  // side extent: width (zigzag) or radius (contour)
  double T = 0;  // forward extent: height (zigzag) or 2 pi (contour)
  double R = 0;  // contour: disk radius

  Eigen::Vector2d uv(double s, double t) const {
    if (!polar) return {s, t};
    const double rho = R - s;
    return {rho * std::cos(t), rho * std::sin(t)};
  }
  // The centre of the disk: a pass of one point.
  bool degenerate(double s) const { return polar && s >= R; }
};

struct Pass {
  double s = 0;
  bool closed = false;  // contour circles: the last vertex is the first one again
  std::vector<double> t;
  std::vector<Eigen::Vector3d> p, n, c;  // contact (lifted with the ball), unit normal, ball centre
  std::vector<double> lift;               // how far the ball was lifted off the interpolant (mm)
  std::vector<double> delta;              // how far the surface may be off there (Margins)
  std::vector<char> unchecked;            // per segment: the forward chord check did not hold
  std::vector<Eigen::Vector2d> uv;        // the rim pass: uv of each vertex (else from Coords)
  std::vector<char> off;                  // per vertex: over a hole of the patch, not cut (the
                                          // segments next to it are not cut either)
  bool cut(std::size_t k) const { return !off[k] && !off[k + 1]; }  // segment k
};

// Where the domain is off the patch, in uv: over a hole, inside the polygon of a hole loop's uv
// images (the map leaves no cloud point there; the interpolant would only extrapolate), and on
// a planar map (param.planar), whose rectangle reaches past the outline, outside the outer
// loop's. Passes are not cut there: the tool lifts over it (post.link).
class OffPatch {
 public:
  // holes  the hole loops' uv polygons (tested as their union); outline  the outer loop's, or
  // none when the map fills its domain with the patch (harmonic maps)
  OffPatch(std::vector<std::vector<Eigen::Vector2d>> holes, std::vector<std::vector<Eigen::Vector2d>> outline)
      : holes_(std::move(holes)), outline_(std::move(outline)) {}
  bool empty() const { return holes_.empty() && outline_.empty(); }
  // (beyond the outline by its nearest edge, a k-d tree search: a ray cast over the thousands of
  // edges of a large cloud's loop for every place the planner looks at took most of its time)
  bool contains(const Eigen::Vector2d& uv) const {
    return (!outline_.empty() && outline_.beyond(uv) > 0) || (!holes_.empty() && holes_.any_contains(uv));
  }

 private:
  Outline holes_, outline_;
};

// Local geometry at a vertex of a pass, and the side step it allows.
struct VertexInfo {
  double ds = kInf;        // parameter side step, formula (3) or (4)
  double interval = kInf;  // surface side interval l_s (mm)
  bool formula4 = false;
  bool unreachable = false;  // smallest normal curvature radius below r (concave)
  double kappa_min = 0;      // smallest principal curvature (convex positive)
};

struct Derivs {
  Eigen::Vector3d p, n, rs, rt, rss, rst, rtt;
  double uncertainty = 0;  // of the surface there: the larger of the planner's and the height field's
  double fit_gap = 0;      // Planner::fit_gap there
};

struct StripCheck {
  double scallop_max = 0;
  Eigen::Vector3d where = Eigen::Vector3d::Zero();
  double interval_min = kInf, interval_max = 0;  // contact of A to contact polyline of B (mm)
};

// Keeps the ball off the cloud: lifts a ball centre along the contact normal until no cloud
// point lies inside the ball. Where the surface is concave with a radius below r (or kinked),
// the ball placed at c = p + r n reaches into the surface beside the contact; lifting it leaves
// material there (reported as a concave region) instead of gouging.
class BallLifter {
 public:
  // tree  a 3-D k-d tree over the cloud P (the height field's: HeightFieldModel::tree3d).
  BallLifter(const std::vector<Eigen::Vector3d>& P, const KdTree<Eigen::Vector3d, 3>& tree, double r)
      : points_(P), tree_(tree), r_(r) {}
  // The smallest d >= 0 such that every cloud point is at least r - tol from c + d n (n unit,
  // tol < r; a negative tol keeps the points |tol| outside the ball).
  double lift(const Eigen::Vector3d& c, const Eigen::Vector3d& n, double tol) const {
    const double rr = r_ - tol;
    std::vector<std::pair<std::uint32_t, double>> hits;
    tree_.radiusSearch(c.data(), rr * rr, hits, nanoflann::SearchParams(32, 0, false));
    double d = 0;
    for (const auto& [i, sq] : hits) {
      // |c + d n - q| = rr  <=>  d^2 + 2 b d + (|c - q|^2 - rr^2) = 0, b = (c - q).n
      const Eigen::Vector3d w = c - points_[i];
      const double b = w.dot(n), k = w.squaredNorm() - rr * rr;
      if (k >= 0) continue;
      d = std::max(d, -b + std::sqrt(b * b - k));
    }
    return d;
  }

 private:
  const std::vector<Eigen::Vector3d>& points_;
  const KdTree<Eigen::Vector3d, 3>& tree_;
  double r_;
};

// The surface the planner sees (the cloud, through the (u,v) interpolant) may lie up to
// delta off the real one, either way: delta = the larger of the surface_error option and how well
// the cloud is known there (cloud.denoise's per-point uncertainty, a bound on noise and shape bias,
// or its height field's where that is smaller; see plan_isoparametric). Then
//   real scallop <= scallop on the estimate + stock + delta, kept <= h - 0.15 delta;
//   real gouge   <= chord overcut + delta - stock, kept <= 0.9 e - 0.15 delta (chord_budget, step_size.h).
// The planner's fit is also checked against the cloud's height field, the surface the gouge guard
// and the certificate use: where they disagree by fit_gap (see Planner::fit_gap), the scallop the
// certificate sees may be that much higher, so it comes off the scallop limit too (up to h/4).
// The gouge side needs no such margin: the guard lifts balls against that height field.
struct Margins {
  double delta;     // mm, how far the estimate may be off here
  double scallop;   // mm, the limit for the scallop on the estimate (stock included): h - 1.15 delta - gap
  double overcut;   // mm, the chord overcut allowed
  double stock;     // mm, how far the ball is kept above the estimate
};
Margins margins(const IsoparametricOptions& o, double uncertainty, double fit_gap = 0) {
  Margins m;
  m.delta = std::max(o.surface_error, uncertainty);
  const double h = o.scallop_height * o.safety_factor;
  // (the certificate adds its height field's uncertainty where it samples, between the places
  // planned: kUncertaintyRoughness more of it is kept, as for the gouge, step_size.h)
  m.scallop = h - ((1 + kUncertaintyRoughness) * m.delta + std::min(fit_gap, 0.25 * h));
  const ChordBudget b = chord_budget(o.chord_error, m.delta);
  m.overcut = b.overcut;
  m.stock = b.stock;
  return m;
}
// Too uncertain to plan for: less than a fifth of h would be left for the scallop itself.
constexpr double kLeastScallopShare = 0.2;
bool too_uncertain(const IsoparametricOptions& o, const Margins& m) {
  return m.scallop - m.stock < kLeastScallopShare * o.scallop_height * o.safety_factor;
}
// The smallest scallop height (mm) a surface known to +-delta can be planned for: the h that
// leaves exactly that share, h - 1.15 delta - stock (Margins) = 0.2 h, rounded up to a micron.
double plannable_scallop_height(const IsoparametricOptions& o, double delta) {
  const double d = std::max(o.surface_error, delta);
  return std::ceil(1000 * ((1 + kUncertaintyRoughness) * d + chord_budget(o.chord_error, d).stock) /
                   ((1 - kLeastScallopShare) * o.safety_factor)) / 1000;
}
// The planner refuses when more than 1 / this of the cloud's points are too uncertain.
constexpr std::size_t kMostlyCertainDivisor = 100;

// The largest uncertainty of the certificate's height field (post.simulate's, the same model) on
// the outer loop's edges, sampled every quarter of the cloud's spacing: the loop runs through the
// outermost points, whose fits are one-sided, and between them the field extrapolates. There the
// certificate's whole-patch bound is hardest to meet: on the noisy waves (sigma 0.02) the points
// are known to +-0.021 mm (99 %) but the field at the outline to +-0.038, and a program planned
// for the points at h = 0.053, 0.06 and 0.07 failed its certificate there (0.073-0.076 mm), one
// planned at h = 0.103 passed. 0 without a usable loop or uncertainty.
double outline_uncertainty(const HeightFieldModel& model, const PointCloud& cloud, const std::vector<int>& loop) {
  if (!cloud.has_uncertainty() || loop.size() < 3) return 0;
  for (int i : loop)
    if (i < 0 || std::size_t(i) >= cloud.size()) return 0;
  const double step = 0.25 * model.spacing();
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, loop.size(), 64), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double worst) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
          const Eigen::Vector2d a = cloud.points[loop[k]].head<2>(), b = cloud.points[loop[(k + 1) % loop.size()]].head<2>();
          const int m = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
          for (int t = 0; t < m; ++t) {
            const Eigen::Vector2d q = a + (b - a) * (double(t) / m);
            double z, u = 0;
            Eigen::Vector3d n;
            model.eval(q.x(), q.y(), z, n, /*force=*/true, &u);
            if (std::isfinite(u)) worst = std::max(worst, u);
          }
        }
        return worst;
      },
      [](double a, double b) { return std::max(a, b); });
}

class Planner {
 public:
  // model  the cloud's height field (post.simulate's model), or null
  Planner(const ParametricSurface& f, const BallLifter& lifter, const HeightFieldModel* model, Coords co,
          const IsoparametricOptions& o, const OffPatch& off_patch, const Outline& hole_edges, const Outline& outer_edge)
      : f_(f), lifter_(lifter), model_(model), off_patch_(off_patch), hole_edges_(hole_edges), outer_edge_(outer_edge),
        co_(co), o_(o), r_(o.tool_radius),
        h_(o.scallop_height * o.safety_factor),
        e_under_(std::min(0.98 * o.chord_error, 0.1 * h_)), hfd_(2 * f.uv_spacing()),
        ls0_(std::sqrt(8 * r_ * h_)) {}

  double chord_overcut_max = 0, chord_undercut_max = 0;
  double forward_min = kInf, forward_max = 0;
  int forward_floor_hits = 0;
  Eigen::Vector3d forward_floor_at = Eigen::Vector3d::Zero();  // the first of them

  SurfaceSample at(double s, double t) const { return f_(co_.uv(s, t)); }
  // off the patch: over a hole, or beyond the outline of a planar map
  bool over_hole(double s, double t) const { return !off_patch_.empty() && off_patch_.contains(co_.uv(s, t)); }
  // How far the planner's fit lies from the cloud's height field (the certificate's model) at x,
  // along the normal; 0 off the field. Where the two disagree the surface is known no better
  // than that: the scallop limit keeps the gap as a margin (Margins). It grows where a fit over
  // the (u, v) map straddles a corner or a squeezed part of the map: measured 0.002 mm beside a
  // 110 degree corner of the freeform patch (a clean cloud), where the scallop came out 3 % over
  // h without it.
  // field_delta, when given, gets the height field's uncertainty there, as the certificate sees it
  // (grown beyond the cloud's edge; 0 without a model).
  double fit_gap(const SurfaceSample& x, double* field_delta = nullptr) const {
    double z, u = 0;
    Eigen::Vector3d n;
    const bool on = model_ && model_->eval(x.position.x(), x.position.y(), z, n, false, &u);
    if (field_delta) *field_delta = u;
    if (!on) return 0;
    const double gap = std::abs(x.position.z() - z) * std::abs(x.normal.z());
    double seen = fit_gap_max_.load(std::memory_order_relaxed);
    while (gap > seen && !fit_gap_max_.compare_exchange_weak(seen, gap)) {
    }
    return gap;
  }
  double fit_gap_max() const { return fit_gap_max_.load(); }
  Margins margin(const SurfaceSample& x) const { return margins(o_, x.uncertainty); }
  // How far a cloud point may reach into the ball before it is lifted: `fraction` of e, and no
  // more than the real gouge allows when the point itself may be delta too low (the gouge
  // budget less delta, as in Margins; negative, i.e. a clearance, where delta is larger).
  double lift_tolerance(double delta, double fraction) const {
    return std::min(fraction * o_.chord_error, gouge_budget(o_.chord_error, delta) - delta);
  }
  // The ball centre over the estimated surface, the stock above it (see Margins).
  Eigen::Vector3d centre(const SurfaceSample& x) const {
    return x.position + (r_ + margin(x).stock) * x.normal;
  }

  // r and its first and second derivatives in (s, t). On a rectangle (s, t) = (u, v): the
  // surface's own (central differences through the interpolant, paper section 3.1, for a
  // cloud). On a disk, central differences in (s, t) = (R - rho, theta), the stencil centre
  // moved off the centre by one step (the polar map is smooth there).
  Derivs derivs(double s, double t) const {
    Derivs d;
    SurfaceSample x;
    if (!co_.polar) {
      const SurfaceDerivatives r = f_.derivatives(co_.uv(s, t));
      x = r.sample;
      d.rs = r.ru, d.rt = r.rv, d.rss = r.ruu, d.rst = r.ruv, d.rtt = r.rvv;
    } else {
      const double hs = hfd_, ht = std::min(0.25, hfd_ / std::max(co_.R - s, 1e-12));
      const double sc = std::max(s, hs), tc = t;
      auto P = [&](double ds, double dt) { return at(sc + ds, tc + dt).position; };
      x = at(s, t);
      const Eigen::Vector3d p0 = sc == s ? x.position : P(0, 0), ps = P(hs, 0), ms = P(-hs, 0), pt = P(0, ht),
                            mt = P(0, -ht);
      d.rs = (ps - ms) / (2 * hs);
      d.rt = (pt - mt) / (2 * ht);
      d.rss = (ps + ms - 2 * p0) / (hs * hs);
      d.rtt = (pt + mt - 2 * p0) / (ht * ht);
      d.rst = (P(hs, ht) - P(hs, -ht) - P(-hs, ht) + P(-hs, -ht)) / (4 * hs * ht);
    }
    d.p = x.position;
    d.n = x.normal;
    double field_delta;
    d.fit_gap = fit_gap(x, &field_delta);
    d.uncertainty = std::max(x.uncertainty, field_delta);
    return d;
  }

  VertexInfo vertex_info(double s, double t) const {
    const Derivs d = derivs(s, t);
    const FundamentalForms ff = fundamental_forms(d.rs, d.rt, d.rss, d.rst, d.rtt, d.n);
    VertexInfo v;
    const double theta = std::acos(std::clamp(ff.F / std::sqrt(ff.E * ff.G), -1.0, 1.0));
    v.formula4 = std::abs(theta - M_PI / 2) > o_.conformal_tolerance * M_PI / 180;
    // Formula (3) takes the side curvature along r_s; formula (4) the one across the pass
    // (perpendicular to r_t on the surface, parameter direction (1, -F/G)).
    const double kappa_s = v.formula4 ? normal_curvature(ff, 1, -ff.F / ff.G)
                                      : normal_curvature(ff, 1, 0);
    // the margin for the estimate's error, and the stock, come off the scallop allowed
    const Margins m = margins(o_, d.uncertainty, d.fit_gap);
    v.interval = side_interval(std::max(m.scallop - m.stock, 0.1 * h_), r_, kappa_s);
    const double rsn = std::sqrt(ff.E);
    v.ds = v.formula4 ? side_step_corrected(v.interval, rsn, theta)
                      : side_step_conformal(v.interval, rsn);
    v.kappa_min = principal_curvatures(ff)[0];
    v.unreachable = ball_cannot_reach(r_, v.kappa_min);
    return v;
  }

  // Largest ratio of the chord deviation of the ball-centre segment c0-c1 (pass s, t0 to t1)
  // to its limit, sampled at 1/4, 1/2 and 3/4, and at least every half sampling step of the map
  // (a denoised cloud keeps small bumps of its residual noise that a long segment can pass
  // over between quarter points); the largest overcut and undercut into over_max, under_max.
  double chord_ratio(double s, double t0, double t1, const Eigen::Vector3d& c0,
                     const Eigen::Vector3d& c1, double& over_max, double& under_max) const {
    over_max = under_max = 0;
    double ratio = 0;
    const Eigen::Vector3d seg = c1 - c0;
    const double L2 = seg.squaredNorm();
    // hfd_ is two sampling steps of the map: a quarter of it is half a step
    const double dt_sample = 0.25 * (co_.polar ? hfd_ / std::max(co_.R - s, hfd_) : hfd_);
    const int parts = std::clamp(static_cast<int>(std::ceil(std::abs(t1 - t0) / dt_sample)), 4, 64);
    for (int k = 1; k < parts; ++k) {
      const SurfaceSample m = at(s, t0 + (t1 - t0) * k / double(parts));
      const Eigen::Vector3d cm = centre(m);
      const double y = L2 > 0 ? std::clamp((cm - c0).dot(seg) / L2, 0.0, 1.0) : 0.0;
      const double up = (c0 + y * seg - cm).dot(m.normal);  // > 0: chord above (undercut)
      const double over = std::max(0.0, -up), under = std::max(0.0, up);
      // Sideways the chord may stray up to e as well (it shifts the pass, not the depth).
      const double total = (c0 + y * seg - cm).norm();
      ratio = std::max(
          {ratio, over / margin(m).overcut, under / e_under_, total / (0.9 * o_.chord_error)});
      over_max = std::max(over_max, over);
      under_max = std::max(under_max, under);
    }
    return ratio;
  }

  // Appends the vertex at t over the surface point x to P. The contact is moved up with the
  // ball where the ball would reach into the cloud; a quarter of e is left to the cloud's noise
  // and the interpolant's error.
  void push_vertex(Pass& P, double t, const SurfaceSample& x, bool off = false) const {
    P.off.push_back(off);
    if (off) {  // not cut: nothing to keep off the cloud
      P.t.push_back(t);
      P.p.push_back(x.position);
      P.n.push_back(x.normal);
      P.c.push_back(x.position + r_ * x.normal);
      P.lift.push_back(0);
      P.delta.push_back(0);
      return;
    }
    const Margins m = margin(x);
    const double d = m.stock + lifter_.lift(centre(x), x.normal, lift_tolerance(m.delta, 0.25));
    P.t.push_back(t);
    P.p.push_back(x.position + d * x.normal);
    P.n.push_back(x.normal);
    P.c.push_back(x.position + (r_ + d) * x.normal);
    P.lift.push_back(d - m.stock);
    P.delta.push_back(m.delta);
  }

  // The rim pass: a closed pass through the outer loop's own points (positions, normals and
  // uncertainties of the cloud, uv from the map), so the ball reaches every point of the
  // cloud's outline, corners included (the interpolant, a local fit, rounds a corner of the
  // outline off by up to half a sampling step, and the passes built from it leave the corner
  // uncut). Every segment is sampled and lifted as an unchecked one (lift_segments): between
  // two outline points there is no interpolant to check the chord against, only the cloud.
  // loop: point indices of a boundary loop, in order; uv: their uv; uncertainty: what the
  // margins are planned with at each cloud point (null: none). Not the point's own: at a corner
  // its one-sided denoising fit said 0.037 where the height field knows 0.015 (the bundled
  // example), and the stock planned for 0.037 left the corner's scallop over h.
  // offset > 0 (an outer loop only): each vertex is moved outward by offset along the surface
  // (offset × n_z in xy; along the bisector of the normals of the chords to the loop's points
  // two spacings back and ahead, mitred up to 2 times at a corner) onto the height field
  // extrapolated there, its uncertainty the larger of the point's and the field's, which grows
  // beyond the cloud's edge.
  Pass rim_pass(const PointCloud& cloud, const std::vector<int>& loop,
                const std::vector<Eigen::Vector2d>& uv, const std::vector<double>* uncertainty,
                double offset = 0, bool hole = false) const {
    Pass P;
    P.closed = true;
    const std::size_t n = loop.size();
    std::vector<Eigen::Vector2d> xy(n);
    for (std::size_t k = 0; k < n; ++k) xy[k] = cloud.points[loop[k]].head<2>();
    // the right of a counter-clockwise loop is outside it: off the patch, but for a hole's loop
    const double away = (twice_signed_area(xy) > 0 ? 1.0 : -1.0) * (hole ? -1.0 : 1.0);
    for (std::size_t k = 0; k <= n; ++k) {
      const int i = loop[k % n];
      SurfaceSample x;
      x.position = cloud.points[i];
      x.normal = cloud.normals[i];
      x.uncertainty = uncertainty ? (*uncertainty)[i] : 0.0;
      if (offset > 0 && model_) {
        // The loop's points ~2 spacings back and ahead: the directions between neighbours are
        // the sample's noise (a mitre over them sent vertices 4 mm out at the freeform's spike).
        const double window = 2 * model_->spacing();
        const Eigen::Vector2d b = x.position.head<2>();
        auto along = [&](int dir) {
          std::size_t j = k % n;
          for (std::size_t steps = 0; steps + 1 < n; ++steps) {
            j = (j + n + dir) % n;
            if ((cloud.points[loop[j]].head<2>() - b).norm() >= window) break;
          }
          return Eigen::Vector2d(cloud.points[loop[j]].head<2>());
        };
        Eigen::Vector2d t0 = b - along(-1), t1 = along(+1) - b;
        if (t0.norm() > 0 && t1.norm() > 0) {
          t0.normalize(), t1.normalize();
          const Eigen::Vector2d n0(t0.y(), -t0.x()), n1(t1.y(), -t1.x());
          Eigen::Vector2d bis = n0 + n1;
          if (bis.norm() > 1e-9) {
            bis.normalize();
            // mitred at a corner, up to 2 times (a 60 degree corner)
            const double mitre = std::min(2.0, 1.0 / std::max(bis.dot(n0), 1e-9));
            const Eigen::Vector2d q = b + away * offset * std::abs(x.normal.z()) * mitre * bis;
            double z, u = 0;
            Eigen::Vector3d nn;
            if (model_->eval(q.x(), q.y(), z, nn, true, &u)) {
              x.position = Eigen::Vector3d(q.x(), q.y(), z);
              x.normal = nn;
              x.uncertainty = std::max(x.uncertainty, u);
            }
          }
        }
      }
      push_vertex(P, static_cast<double>(k), x);
      P.uv.push_back(uv[k % n]);
      if (k) P.unchecked.push_back(true);
    }
    lift_segments(P);
    join_ends(P);
    return P;
  }

  Pass build_pass(double s) {
    Pass P;
    P.s = s;
    P.closed = co_.polar;
    if (co_.degenerate(s)) {
      P.closed = false;
      push_vertex(P, 0, at(s, 0), over_hole(s, 0));
      return P;
    }
    double t = 0;
    SurfaceSample x = at(s, 0);
    bool off = over_hole(s, 0);
    push_vertex(P, 0, x, off);
    const double dt_floor = 1e-3 * hfd_ / (co_.polar ? std::max(co_.R - s, hfd_) : 1.0);
    // Over a hole the pass moves on in steps of two sampling steps of the map until it is back
    // on the patch; the hole's edge is then found by bisection, to a thousandth of a step.
    const double dt_hole = co_.polar ? hfd_ / std::max(co_.R - s, hfd_) : hfd_;
    auto edge = [&](double t_in, double t_out) {  // t_in on the patch, t_out over the hole
      for (int i = 0; i < 10; ++i) {
        const double m = 0.5 * (t_in + t_out);
        (over_hole(s, m) ? t_out : t_in) = m;
      }
      return std::pair{t_in, t_out};
    };
    // a vertex at t1 without a chord check (the segment to it crosses a hole's edge)
    auto step_over = [&](double t1, bool off1) {
      x = at(s, t1);
      P.unchecked.push_back(false);
      push_vertex(P, t1, x, off1);
      t = t1;
      off = off1;
    };
    while (t < co_.T) {
      if (off) {
        const double t1 = std::min(co_.T, t + dt_hole);
        const bool off1 = over_hole(s, t1);
        step_over(off1 ? t1 : edge(t1, t).first, off1);
        continue;
      }
      // Formula (2) from the pass's own curvature gives the first guess.
      const double ht = co_.polar ? std::min(0.25, hfd_ / std::max(co_.R - s, 1e-12)) : hfd_;
      const double tc = co_.polar ? t : std::clamp(t, ht, co_.T - ht);
      // (x is the surface at (s, t): not evaluated again where the stencil is centred there)
      const Eigen::Vector3d p0 = tc == t ? x.position : at(s, tc).position, pp = at(s, tc + ht).position,
                            pm = at(s, tc - ht).position;
      const Eigen::Vector3d rt = (pp - pm) / (2 * ht), rtt = (pp + pm - 2 * p0) / (ht * ht);
      const double rtn = std::max(rt.norm(), 1e-12);
      const double kappa = rt.cross(rtt).norm() / (rtn * rtn * rtn);
      const bool convex = rtt.dot(x.normal) < 0;  // chord below the curve: overcut
      // Concave along the pass with a radius below r: the centre curve folds back on itself and
      // no chord check is meaningful (the place is reported as a concave region).
      const bool folded = ball_cannot_reach(r_, -rtt.dot(x.normal) / (rtn * rtn));
      // Formula (2) bounds the chord of the contact curve; the ball centre runs on the offset
      // curve, whose chords are (1 + r kappa_n) times longer at radius (R + r): its sagitta is
      // that of a contact curve of curvature kappa (1 + r kappa_n).
      const double kappa_n = -rtt.dot(x.normal) / (rtn * rtn);
      const double lf = std::min(
          forward_interval(convex ? margin(x).overcut : e_under_,
                           kappa * std::abs(1 + r_ * kappa_n)),
          o_.max_segment);
      double dt = lf / rtn;
      if (co_.polar) dt = std::min(dt, M_PI / 8);
      dt = std::max(dt, dt_floor);
      bool last = t + dt * (1 + 1e-6) >= co_.T;
      if (last) dt = co_.T - t;
      else if (t + 1.5 * dt > co_.T) dt = (co_.T - t) / 2;  // no sliver of a last step
      if (!off_patch_.empty() && over_hole(s, t + dt)) {
        // The step would end over a hole: it ends at the hole's edge instead, or, standing on
        // the edge already, the pass steps into the hole (that segment is not cut).
        const auto [t_in, t_out] = edge(t, t + dt);
        if (t_in - t <= 1e-3 * dt) {
          step_over(t_out, true);
          continue;
        }
        dt = t_in - t;
        last = false;
      }
      SurfaceSample x1;
      bool unchecked = folded;
      double over = 0, under = 0;  // the chord deviations of the step taken
      for (int iter = 0;; ++iter) {
        x1 = at(s, last ? co_.T : t + dt);
        if (folded) break;
        const double ratio = chord_ratio(s, t, t + dt, centre(x), centre(x1), over, under);
        if (ratio <= 1) break;
        if (dt <= dt_floor || iter >= 40) {
          if (forward_floor_hits++ == 0) forward_floor_at = x.position;
          unchecked = true;
          break;
        }
        dt = std::max(dt_floor, dt * std::clamp(0.99 / std::sqrt(ratio), 0.2, 0.99));
        last = false;
      }
      chord_overcut_max = std::max(chord_overcut_max, over);
      chord_undercut_max = std::max(chord_undercut_max, under);
      const double len = (x1.position - x.position).norm();
      forward_min = std::min(forward_min, len);
      forward_max = std::max(forward_max, len);
      t = last ? co_.T : t + dt;
      x = x1;
      P.unchecked.push_back(unchecked);
      push_vertex(P, t, x);
      const std::size_t cap = std::min<std::size_t>(kMaxPassPoints, o_.max_points);
      if (P.t.size() > cap)
        throw std::invalid_argument(
            "a pass (s = " + short_number(s, 6) + ") needs more than " + std::to_string(cap) +
            " points: the forward step fell to " + short_number(len, 6) +
            " mm; the UV map is degenerate there or the cloud too noisy for chord_error " +
            short_number(o_.chord_error, 6) + " mm (smooth or clean the cloud, or raise chord_error)");
      if (o_.progress && P.t.size() % 5000 == 0)
        o_.progress(std::min(0.99, s / co_.S),
                    "pass at s = " + short_number(s, 6) + ": " + std::to_string(P.t.size()) + " points so far");
    }
    lift_segments(P);
    if (P.closed) join_ends(P);
    return P;
  }

  // The two ends of a closed pass are one vertex: both get the higher of their two lifts.
  static void join_ends(Pass& P) {
    if (P.c.size() < 2) return;
    const std::size_t last = P.c.size() - 1, from = P.lift[last] > P.lift[0] ? last : 0;
    for (std::size_t j : {std::size_t{0}, last})
      P.c[j] = P.c[from], P.p[j] = P.p[from], P.n[j] = P.n[from], P.lift[j] = P.lift[from];
  }

  // The swept ball between two lifted vertices can still reach more than e into the cloud (a
  // concave place narrower than the step): sample each centre segment about every r/16 and lift
  // both of its ends by what the worst sample needs, a few rounds (lifting one segment moves
  // its neighbours' ends).
  void lift_segments(Pass& P) const {
    const double step = r_ / 16;
    for (int round = 0; round < 8; ++round) {
      bool moved = false;
      for (std::size_t k = 0; k + 1 < P.c.size(); ++k) {
        // Only next to lifted vertices and where the forward chord check did not hold:
        // elsewhere that check already bounds the overcut, and lifting for it would only add
        // to the scallop.
        if (!P.cut(k) || (P.lift[k] <= 0 && P.lift[k + 1] <= 0 && !P.unchecked[k])) continue;
        const Eigen::Vector3d a = P.c[k], b = P.c[k + 1];
        const Eigen::Vector3d n = (P.n[k] + P.n[k + 1]).normalized();
        const int m = std::max(2, static_cast<int>(std::ceil((b - a).norm() / step)));
        double d = 0;
        // The chord may cut up to e below the centre curve (the forward step allows that); half
        // of it is kept back for the cloud between the samples.
        // (the ends too: lifting a vertex along its own normal can bring it nearer the cloud
        // elsewhere)
        const double tol = lift_tolerance(std::max(P.delta[k], P.delta[k + 1]), 0.5);
        for (int i = 0; i <= m; ++i)
          d = std::max(d, lifter_.lift(a + (b - a) * (double(i) / m), n, tol));
        if (d <= 0) continue;
        moved = true;
        for (std::size_t j : {k, k + 1}) {
          // lift along the vertex normal by enough to raise it d along n
          const double dj = d / std::max(0.5, P.n[j].dot(n));
          P.c[j] += dj * P.n[j];
          P.p[j] += dj * P.n[j];
          P.lift[j] += dj;
        }
      }
      if (!moved) break;
    }
  }

  // Calls fn(a, b) for the segments (or the single point) of polyline V of pass P that may lie
  // within `reach` of o: the segment containing t, its neighbours, and on outwards while the
  // segments stay within reach.
  template <class Fn>
  void near_segments(const Pass& P, const std::vector<Eigen::Vector3d>& V, double t,
                     const Eigen::Vector3d& o, double reach, Fn&& fn) const {
    const int nv = static_cast<int>(V.size());
    if (nv == 1) {
      if (!P.off[0]) fn(V[0], V[0]);
      return;
    }
    const int nseg = nv - 1;
    int k = static_cast<int>(std::upper_bound(P.t.begin(), P.t.end(), t) - P.t.begin()) - 1;
    k = std::clamp(k, 0, nseg - 1);
    auto seg_dist = [&](int j) {
      const Eigen::Vector3d ab = V[j + 1] - V[j];
      const double L2 = ab.squaredNorm();
      const double y = L2 > 0 ? std::clamp((o - V[j]).dot(ab) / L2, 0.0, 1.0) : 0.0;
      return (o - V[j] - y * ab).norm();
    };
    // segments over a hole are not cut (the tool lifts there)
    if (P.cut(k)) fn(V[k], V[k + 1]);
    for (int dir = -1; dir <= 1; dir += 2) {
      for (int step = 1; step < nseg; ++step) {
        int j = k + dir * step;
        if (P.closed) j = ((j % nseg) + nseg) % nseg;
        else if (j < 0 || j >= nseg) break;
        if (j == k) break;
        if (step > 1 && seg_dist(j) > reach) break;
        if (P.cut(j)) fn(V[j], V[j + 1]);
      }
    }
  }

  // Height of material left above the surface point at (s, t) by the balls swept along the
  // centre polylines of A and B, per pass: the first hit of the normal ray (verify.py's
  // definition of the scallop); +infinity where the ray misses.
  Eigen::Vector2d hits_at(const Pass& A, const Pass& B, double s, double t,
                          SurfaceSample* where) const {
    const SurfaceSample x = at(s, t);
    if (where) *where = x;
    Eigen::Vector2d hit(kInf, kInf);
    const double reach = r_ + 20 * h_;
    near_segments(A, A.c, t, x.position, reach, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      hit[0] = std::min(hit[0], ray_capsule_entry(x.position, x.normal, a, b, r_, hit[0]));
    });
    near_segments(B, B.c, t, x.position, reach, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      hit[1] = std::min(hit[1], ray_capsule_entry(x.position, x.normal, a, b, r_, hit[1]));
    });
    return hit;
  }

  // Largest scallop between passes A and B, looked for across the strip at sample positions
  // along A (four per segment, at most half the nominal interval apart) and at B's vertices.
  StripCheck check_strip(const Pass& A, const Pass& B) const {
    std::vector<double> ts;
    for (std::size_t k = 0; k + 1 < A.t.size(); ++k) {
      // (off the patch A's segments are long, and beyond a planar map's outline the places
      // between the rim pass and B lie beside them: sampled as finely as on it)
      if (!A.cut(k) && !rim_tree_) {
        ts.push_back(A.t[k]);
        continue;
      }
      const double len = (A.c[k + 1] - A.c[k]).norm();
      const int n = std::max(4, static_cast<int>(std::ceil(len / (0.5 * ls0_))));
      for (int i = 0; i < n; ++i) ts.push_back(A.t[k] + (A.t[k + 1] - A.t[k]) * i / n);
    }
    ts.push_back(A.t.back());
    if (B.t.size() > 1) ts.insert(ts.end(), B.t.begin(), B.t.end());

    std::vector<double> best(ts.size(), 0);
    std::vector<Eigen::Vector3d> where(ts.size());
    const double sA = A.s, sB = B.s;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ts.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const double t = ts[i];
        // Over a hole there is no surface to leave a scallop on, and within half the nominal
        // interval of its edge the hole's rim pass cuts, between the ends of the passes' pieces
        // (checked against A and B alone, the strips beside a hole's edge were stepped finer
        // than the rest: the waves with two holes, 50 000 points, 107 zig-zag passes, now 104;
        // the dome with two, contour efficiency 0.754, now 0.774; both pass verify.py).
        bool on_patch = false;  // whether a place across the strip so far lies on the patch
        bool near_rim = false;  // whether a place across it is within the reach of the rim pass's balls
        auto g = [&](double f, SurfaceSample* w) {
          if (over_hole(sA + f * (sB - sA), t)) {
            if (w) *w = at(sA + f * (sB - sA), t);
            return Eigen::Vector2d(0, 0);
          }
          Eigen::Vector2d hits = hits_at(A, B, sA + f * (sB - sA), t, w);
          const SurfaceSample here = w ? *w : at(sA + f * (sB - sA), t);
          const Eigen::Vector2d xy = here.position.head<2>();
          if (!hole_edges_.empty() && hole_edges_.beyond(xy) < 0.5 * ls0_) return Eigen::Vector2d(0, 0);
          // the rim pass's balls leave less than A's and B's here (farther off, their material is
          // over (1.5 l)^2 / 8r = 2.25 h)
          if (rim_tree_ && outer_edge_.edge_distance(xy) < 1.5 * ls0_) {
            const double rim = rim_hit(here);
            hits = hits.cwiseMin(Eigen::Vector2d(rim, rim));
            near_rim = true;
          }
          on_patch = true;
          return hits;
        };
        // Coarse scan across the strip; the cusp is where the first hit passes from A's balls
        // to B's, a root of hit_A - hit_B (smooth across the strip) found by regula falsi with
        // the Illinois modification (superlinear, and the root stays bracketed).
        constexpr int kScan = 8;
        double gmax = 0;
        SurfaceSample w, x;
        double f_lo = -1, f_hi = -1, d_lo = 0, d_hi = 0;
        double prev_f = 0, prev_d = -kInf;  // at f = 0 the point touches A's ball
        auto consider = [&](const Eigen::Vector2d& h) {  // false where a ray misses: uncut
          const double v = std::min(h[0], h[1]);
          if (!std::isfinite(v)) {
            gmax = kUncut, w = x;
            return false;
          }
          if (v > gmax) gmax = v, w = x;
          return true;
        };
        bool cut = true;
        double scanned[kScan] = {};  // the material left at each scanned place (the rim's search below)
        for (int j = 1; j < kScan && cut; ++j) {
          const double f = double(j) / kScan;
          const bool before = on_patch;
          const Eigen::Vector2d h = g(f, &x);
          if (!before && on_patch) w = x;  // the first place on the patch, until a higher one
          cut = consider(h);
          scanned[j] = std::min(h[0], h[1]);
          const double d = h[0] - h[1];
          if (cut && f_lo < 0 && prev_d <= 0 && d > 0) f_lo = prev_f, f_hi = f, d_lo = prev_d, d_hi = d;
          prev_f = f, prev_d = d;
        }
        if (cut && f_lo < 0 && prev_d <= 0) f_lo = prev_f, f_hi = 1, d_lo = prev_d, d_hi = kInf;  // crossing next to B
        if (cut && f_lo >= 0) {
          // to a 2^-17 of the strip (the cusp's height is then within a micron of a micron)
          int side = 0;
          for (int it = 0; it < 24 && f_hi - f_lo > 0x1p-17; ++it) {
            double fm = 0.5 * (f_lo + f_hi);  // bisection where an end is not finite
            if (std::isfinite(d_lo) && std::isfinite(d_hi) && d_hi > d_lo)
              fm = std::clamp(f_lo - d_lo * (f_hi - f_lo) / (d_hi - d_lo), f_lo + 0.01 * (f_hi - f_lo),
                              f_hi - 0.01 * (f_hi - f_lo));
            const Eigen::Vector2d h = g(fm, &x);
            if (!consider(h)) break;
            const double d = h[0] - h[1];
            if (d <= 0) {
              f_lo = fm, d_lo = d;
              if (side == -1) d_hi *= 0.5;  // Illinois: the end kept twice has its value halved
              side = -1;
            } else {
              f_hi = fm, d_hi = d;
              if (side == 1) d_lo *= 0.5;
              side = 1;
            }
          }
        }
        if (cut && near_rim) {
          // Beside the rim pass the material left is the least of three hits (A's, the rim's,
          // B's), whose highest may lie at the rim's cusp with A or with B, not where A's and B's
          // cross: searched for around the highest scanned place, by golden section.
          const int j_best = static_cast<int>(std::max_element(scanned + 1, scanned + kScan) - scanned);
          double lo = double(j_best - 1) / kScan, hi = double(j_best + 1) / kScan;
          auto height = [&](double f) {
            const Eigen::Vector2d h = g(f, &x);
            if (!consider(h)) cut = false;
            return std::min(h[0], h[1]);
          };
          constexpr double kGold = 0.6180339887498949;
          double a = hi - kGold * (hi - lo), b = lo + kGold * (hi - lo), ha = height(a), hb = height(b);
          for (int it = 0; it < 14 && cut; ++it) {
            if (ha >= hb) hi = b, b = a, hb = ha, a = hi - kGold * (hi - lo), ha = height(a);
            else lo = a, a = b, ha = hb, b = lo + kGold * (hi - lo), hb = height(b);
          }
        }
        // on the real surface the scallop may be up to delta higher, and on the certificate's
        // height field up to fit_gap (see Margins); across a hole nothing (the margins of the
        // field extrapolated into it had held a strip beside a hole over the limit: 0.058 mm,
        // taken as the formula's step, which left 0.051 along the whole strip)
        if (!on_patch) continue;
        double field_delta;
        const double gap = fit_gap(w, &field_delta);
        best[i] = gmax + h_ - margins(o_, std::max(w.uncertainty, field_delta), gap).scallop;
        where[i] = w.position;
      }
    });
    StripCheck out;
    for (std::size_t i = 0; i < ts.size(); ++i)
      if (best[i] > out.scallop_max) out.scallop_max = best[i], out.where = where[i];

    // Side interval on the surface: each contact of A to the contact polyline of B.
    for (std::size_t k = 0; k < A.p.size(); ++k) {
      if (A.off[k]) continue;
      double d = kInf;
      near_segments(B, B.p, A.t[k], A.p[k], kInf, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        const Eigen::Vector3d ab = b - a;
        const double L2 = ab.squaredNorm();
        const double y = L2 > 0 ? std::clamp((A.p[k] - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
        d = std::min(d, (A.p[k] - a - y * ab).norm());
      });
      if (!std::isfinite(d)) continue;  // B is over a hole there
      out.interval_min = std::min(out.interval_min, d);
      out.interval_max = std::max(out.interval_max, d);
    }
    return out;
  }

  std::vector<VertexInfo> infos(const Pass& P) const {
    std::vector<VertexInfo> v(P.t.size());
    if (co_.degenerate(P.s)) return v;  // the centre point: no side step from it
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.t.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i)
                          if (!P.off[i]) v[i] = vertex_info(P.s, P.t[i]);
                      });
    return v;
  }

  double h() const { return h_; }
  double nominal_interval() const { return ls0_; }

  // A planar map's rim pass, planned before the passes: its passes end on the outline at any
  // angle, and what lies between the rim pass and the passes' ends is no strip between two
  // passes, so near the outline the strips are checked against the rim's balls too (skipped
  // there instead, as beside a hole, the bundled example's corner kept 0.0447 + 0.0107 of its
  // uncertainty between the rim pass and the first pass 1 mm inside it).
  void set_rim(const Pass& rim) {
    for (std::size_t k = 0; k + 1 < rim.c.size(); ++k) {
      if (!rim.cut(k)) continue;
      rim_a_.push_back(rim.c[k]);
      rim_b_.push_back(rim.c[k + 1]);
      rim_mid_.push_back(0.5 * (rim.c[k] + rim.c[k + 1]));
      rim_half_max_ = std::max(rim_half_max_, 0.5 * (rim.c[k + 1] - rim.c[k]).norm());
    }
    if (rim_mid_.empty()) return;
    rim_adaptor_ = std::make_unique<PointsAdaptor<Eigen::Vector3d>>(PointsAdaptor<Eigen::Vector3d>{rim_mid_});
    rim_tree_ = std::make_unique<KdTree<Eigen::Vector3d, 3>>(3, *rim_adaptor_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    rim_tree_->buildIndex();
  }

 private:
  const ParametricSurface& f_;
  const BallLifter& lifter_;
  const HeightFieldModel* model_;
  const OffPatch& off_patch_;
  const Outline& hole_edges_;  // the hole loops in xy: beyond() is the distance to their edges off them
  const Outline& outer_edge_;  // a planar map's outer loop in xy (whose rim pass cuts near it), else none
  // the rim pass's cut centre segments (set_rim), their midpoints in a k-d tree
  std::vector<Eigen::Vector3d> rim_a_, rim_b_, rim_mid_;
  double rim_half_max_ = 0;
  std::unique_ptr<PointsAdaptor<Eigen::Vector3d>> rim_adaptor_;
  std::unique_ptr<KdTree<Eigen::Vector3d, 3>> rim_tree_;
  // The first entry of the ray up the normal from x into the rim pass's swept balls; kInf where
  // none reaches (or there is no rim).
  double rim_hit(const SurfaceSample& x) const {
    if (!rim_tree_) return kInf;
    const double reach = r_ + 20 * h_ + rim_half_max_;
    std::vector<std::pair<std::uint32_t, double>> near;
    rim_tree_->radiusSearch(x.position.data(), reach * reach, near, nanoflann::SearchParams(32, 0, false));
    double hit = kInf;
    for (const auto& [j, d2] : near) hit = std::min(hit, ray_capsule_entry(x.position, x.normal, rim_a_[j], rim_b_[j], r_, hit));
    return hit;
  }
  mutable std::atomic<double> fit_gap_max_{0};
  Coords co_;
  const IsoparametricOptions& o_;
  double r_, h_, e_under_, hfd_, ls0_;
};

// Concave places the ball cannot reach, grouped into regions: points closer than `link` are
// in the same region.
nlohmann::json concave_regions(const std::vector<Eigen::Vector3d>& pts,
                               const std::vector<double>& radius, double link) {
  const int n = static_cast<int>(pts.size());
  std::vector<int> parent(n);
  for (int i = 0; i < n; ++i) parent[i] = i;
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto key = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const long long x = static_cast<long long>(std::floor(p.x() / link)) + dx;
    const long long y = static_cast<long long>(std::floor(p.y() / link)) + dy;
    const long long z = static_cast<long long>(std::floor(p.z() / link)) + dz;
    return (x * 73856093LL) ^ (y * 19349663LL) ^ (z * 83492791LL);
  };
  std::unordered_map<long long, std::vector<int>> grid;
  for (int i = 0; i < n; ++i) grid[key(pts[i], 0, 0, 0)].push_back(i);
  for (int i = 0; i < n; ++i)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid.find(key(pts[i], dx, dy, dz));
          if (it == grid.end()) continue;
          for (int j : it->second)
            if (j > i && (pts[i] - pts[j]).norm() <= link) parent[find(i)] = find(j);
        }
  std::unordered_map<int, int> region_of;
  struct Region {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), lo = Eigen::Vector3d::Constant(kInf),
                    hi = Eigen::Vector3d::Constant(-kInf);
    int count = 0;
    double min_radius = kInf;
  };
  std::vector<Region> regions;
  for (int i = 0; i < n; ++i) {
    const int root = find(i);
    auto [it, fresh] = region_of.emplace(root, static_cast<int>(regions.size()));
    if (fresh) regions.emplace_back();
    Region& g = regions[it->second];
    g.sum += pts[i];
    g.lo = g.lo.cwiseMin(pts[i]);
    g.hi = g.hi.cwiseMax(pts[i]);
    ++g.count;
    g.min_radius = std::min(g.min_radius, radius[i]);
  }
  nlohmann::json list = nlohmann::json::array();
  for (const Region& g : regions) {
    const Eigen::Vector3d c = g.sum / g.count;
    list.push_back({{"centre", {c.x(), c.y(), c.z()}},
                    {"bbox_min", {g.lo.x(), g.lo.y(), g.lo.z()}},
                    {"bbox_max", {g.hi.x(), g.hi.y(), g.hi.z()}},
                    {"points", g.count},
                    {"min_radius", g.min_radius}});
  }
  return {{"count", regions.size()}, {"points", n}, {"regions", list}};
}

void check_options(const IsoparametricOptions& o) {
  auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string(what) + " must be positive (got " + short_number(v, 6) + ")");
  };
  positive(o.tool_radius, "tool_radius");
  positive(o.scallop_height, "scallop_height");
  positive(o.chord_error, "chord_error");
  positive(o.max_segment, "max_segment");
  if (o.scallop_height >= o.tool_radius)
    throw std::invalid_argument("scallop_height (" + short_number(o.scallop_height, 6) +
                                " mm) must be smaller than tool_radius (" + short_number(o.tool_radius, 6) +
                                " mm)");
  if (!(o.safety_factor > 0 && o.safety_factor <= 1))
    throw std::invalid_argument("safety_factor must be in (0, 1] (got " + short_number(o.safety_factor, 6) + ")");
  if (!(o.surface_error >= 0) || !std::isfinite(o.surface_error))
    throw std::invalid_argument("surface_error must be >= 0 (got " + short_number(o.surface_error, 6) + ")");
  if (too_uncertain(o, margins(o, 0)))
    throw std::invalid_argument(
        "surface_error " + short_number(o.surface_error, 6) + " mm leaves too little of the scallop height " +
        short_number(o.scallop_height, 6) + " mm (times safety_factor " + short_number(o.safety_factor, 6) +
        ") to plan for: raise scallop_height or lower surface_error");
  if (!(o.conformal_tolerance >= 0 && o.conformal_tolerance < 90))
    throw std::invalid_argument("conformal_tolerance must be in [0, 90) degrees (got " +
                                short_number(o.conformal_tolerance, 6) + ")");
}

// How much a plan will take, estimated before planning from the cloud's area and the side interval
// on a plane at the median uncertainty: lower bounds (curvature only shortens the intervals).
struct WorkEstimate {
  double area = 0;           // mm^2: sum over the points of pi D^2 / k, D the k-th neighbour's distance
  double side_interval = 0;  // mm
  double side_extent = 0;    // mm the passes are stepped across: the rectangle's edges along u, or
                             // the disk's perimeter / 2 pi
  double passes = 0, length = 0, points = 0;  // passes: lines, ceil(extent / interval) + 1;
                                               // length = area / interval, points = length / max_segment
};

WorkEstimate estimate_work(const PointCloud& cloud, const Neighborhoods& nb, const UVMap& map,
                           const IsoparametricOptions& o, const Margins& m) {
  WorkEstimate w;
  if (nb.k > 0)
    for (std::size_t i = 0; i < nb.size(); ++i) w.area += M_PI * nb.sq_dist(i, nb.k - 1) / nb.k;
  const double h = o.scallop_height * o.safety_factor;
  w.side_interval = side_interval(std::max(m.scallop - m.stock, 0.1 * h), o.tool_radius, 0);
  const std::size_t n = map.outer_loop.size();
  double along_u = 0, perimeter = 0;
  for (std::size_t k = 0; k < n && map.boundary_uv.size() == n; ++k) {
    const int a = map.outer_loop[k], b = map.outer_loop[(k + 1) % n];
    if (a < 0 || b < 0 || static_cast<std::size_t>(std::max(a, b)) >= cloud.size()) continue;
    const double len = (cloud.points[a] - cloud.points[b]).norm();
    perimeter += len;
    const Eigen::Vector2d d = map.boundary_uv[(k + 1) % n] - map.boundary_uv[k];
    if (std::abs(d.x()) > std::abs(d.y())) along_u += len;
  }
  w.side_extent = map.domain == "disk" ? perimeter / (2 * M_PI) : map.domain == "planar" ? map.width : along_u / 2;
  w.passes = std::ceil(w.side_extent / w.side_interval) + 1;  // pass lines, both ends included
  w.length = w.area / w.side_interval;
  w.points = w.length / o.max_segment;
  return w;
}

}  // namespace

IsoparametricResult plan_isoparametric(const PointCloud& cloud, const Neighborhoods& neighbors,
                                       const UVMap& map, const IsoparametricOptions& o,
                                       const BoundaryLoops* loops,
                                       const std::vector<double>* given_field_uncertainty) {
  // ---- input checks -------------------------------------------------------------------------
  if (o.pattern != "zigzag" && o.pattern != "contour")
    throw std::invalid_argument("unknown pattern '" + o.pattern + "' (zigzag or contour)");
  check_options(o);
  if (cloud.size() == 0) throw std::invalid_argument("the cloud is empty");
  if (!cloud.has_normals())
    throw std::invalid_argument("the cloud has no normals; estimate them first (cloud.normals)");
  if (neighbors.size() != cloud.size())
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(neighbors.size()) +
                                " points; the cloud has " + std::to_string(cloud.size()));
  if (map.uv.size() != cloud.size())
    throw std::invalid_argument("the UV map has " + std::to_string(map.uv.size()) +
                                " points; the cloud has " + std::to_string(cloud.size()));
  const bool planar = map.domain == "planar";
  const std::string want = o.pattern == "zigzag" ? "rectangle" : "disk";
  if (map.domain != want && !(planar && o.pattern == "zigzag"))
    throw std::invalid_argument(
        "pattern '" + o.pattern + "' needs a UV map on a " + want + (o.pattern == "zigzag" ? " or a planar map" : "") +
        "; this map's domain is '" + map.domain + "' (" +
        (o.pattern == "zigzag" ? "use pattern 'contour', or map the boundary to a rectangle"
                               : "use pattern 'zigzag', or map the boundary to a disk") +
        ")");
  UVDomain domain;
  Coords co;
  if (want == "rectangle") {  // or planar
    if (!(map.width > 0 && map.height > 0 && std::isfinite(map.width) && std::isfinite(map.height)))
      throw std::invalid_argument("the rectangle map has no area (width " + short_number(map.width, 6) +
                                  ", height " + short_number(map.height, 6) + ")");
    domain.kind = UVDomain::Kind::Rectangle;
    domain.width = map.width;
    domain.height = map.height;
    co.S = map.width;
    co.T = map.height;
  } else {
    if (!(map.radius > 0 && std::isfinite(map.radius)))
      throw std::invalid_argument("the disk map has no area (radius " + short_number(map.radius, 6) + ")");
    domain.kind = UVDomain::Kind::Disk;
    domain.radius = map.radius;
    co.polar = true;
    co.R = co.S = map.radius;
    co.T = kTwoPi;
  }

  if (!cloud.uncertainty.empty() && !cloud.has_uncertainty())
    throw std::invalid_argument("the cloud has " + std::to_string(cloud.size()) + " points but " +
                                std::to_string(cloud.uncertainty.size()) + " uncertainties");
  // The cloud's height field (what the gouge guard and the certificate measure against; shared
  // with them) and the ball lifter, which searches the field's 3-D tree.
  const std::shared_ptr<const HeightFieldModel> model = cloud_height_field(cloud);
  const BallLifter lifter(cloud.points, model->tree3d(), o.tool_radius);
  // How well each point is known: the smaller of its own uncertainty and the height field's there
  // (the band the guard keeps the ball out of and the certificate adds). At a rim or a corner a
  // point's one-sided denoising fit may say 0.08 mm where the field over its neighbours knows
  // 0.028 (the noisy dome; the bundled example's corner 0.037 and 0.015), and a stock planned
  // for the larger left the rim's scallop over h. Where the field's fit misfits the points (a
  // crest tighter than its 20 neighbours) its uncertainty counts the misfit three times and may
  // be ten times the point's own; planning with it refused clean crests that the guard and the
  // certificate handle (more than 1 % of their points "known too poorly").
  if (given_field_uncertainty && given_field_uncertainty->size() != cloud.size())
    throw std::invalid_argument("the height field's uncertainty is given at " +
                                std::to_string(given_field_uncertainty->size()) + " places for a cloud of " +
                                std::to_string(cloud.size()) + " points");
  std::vector<double> field_uncertainty;
  if (cloud.has_uncertainty() && !given_field_uncertainty) {
    field_uncertainty.resize(cloud.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        double z, u = 0;
        Eigen::Vector3d n;
        model->eval(cloud.points[i].x(), cloud.points[i].y(), z, n, true, &u);
        field_uncertainty[i] = u;
      }
    });
  }
  std::vector<double> known, planned;
  if (cloud.has_uncertainty()) {
    const std::vector<double>& field = given_field_uncertainty ? *given_field_uncertainty : field_uncertainty;
    known.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) known[i] = std::min(field[i], cloud.uncertainty[i]);
    // The margins take the largest over the point and its nearest neighbours: the field's
    // uncertainty is rough (a fit over another set of neighbours a tenth of a mm away may know
    // 20 % less), and the certificate sees it between the places planned (with each point's own
    // value the bundled example's zig-zag certificate failed: 0.0352 + 0.0163 at a place inside).
    planned = known;
    if (neighbors.size() == cloud.size())
      for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int j = 0; j < neighbors.k; ++j) planned[i] = std::max(planned[i], known[neighbors.index(i, j)]);
  }
  const std::vector<double>* planned_uncertainty = cloud.has_uncertainty() ? &planned : nullptr;
  // How well the surface is known (before the neighbours' are taken: a few poorly known points
  // are not many): the planner keeps a margin of delta wherever it plans.
  std::vector<double> deltas;
  std::size_t uncertain = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Margins m = margins(o, known.empty() ? 0.0 : known[i]);
    deltas.push_back(m.delta);
    if (too_uncertain(o, m)) ++uncertain;
  }
  std::nth_element(deltas.begin(), deltas.begin() + deltas.size() / 2, deltas.end());
  const double delta_median = deltas[deltas.size() / 2];
  const double delta_max = *std::max_element(deltas.begin(), deltas.end());
  // The delta that all but 1 / kMostlyCertainDivisor of the points are known to (for the
  // refusals below only): the scallop height it needs is the least that both let through.
  auto p99_delta = [&] {
    const std::size_t p99 = deltas.size() - 1 - deltas.size() / kMostlyCertainDivisor;
    std::nth_element(deltas.begin(), deltas.begin() + p99, deltas.end());
    return deltas[p99];
  };
  // The scallop height the certificate's whole-patch bound needs at the outline, where the
  // surface is known worst (outline_uncertainty), when that is more than `points_need`.
  const double rim_delta = outline_uncertainty(*model, cloud, map.outer_loop);
  const double rim_height = plannable_scallop_height(o, rim_delta);
  auto whole_patch_advice = [&](double points_need) -> std::string {
    if (!(rim_height > std::max(points_need, o.scallop_height))) return "";
    return "; " + short_number(rim_height, 6) + " mm for a certificate of the whole patch, whose outline is known only to +-" +
           short_number(rim_delta, 6) + " mm";
  };
  if (too_uncertain(o, margins(o, delta_median))) {
    const double points_need = plannable_scallop_height(o, p99_delta());
    throw std::invalid_argument(
        "the cloud's surface is known only to +-" + short_number(delta_median, 6) + " mm (median; cloud.denoise's "
        "uncertainty or its height field's, the smaller), too much of the scallop height " + short_number(o.scallop_height, 6) +
        " mm to promise it: denoise with more neighbours, scan more finely or raise scallop_height (to at least " +
        short_number(points_need, 6) + " mm for 99 % of the points" + whole_patch_advice(points_need) + ")");
  }
  // Where more than 1 % of the points are too uncertain, nearly every strip crosses some of
  // them and fails at every side step (measured on a noisy plane, sigma 0.02: at h 0.06, 28 % of
  // its points, all 155 strips failed in 553 s; at h 0.086, 4.75 %, 118 of 130 in 428 s; both
  // certificates failed); say so at once, with the scallop height the points need at least.
  if (uncertain > deltas.size() / kMostlyCertainDivisor) {
    const double delta_p99 = p99_delta(), points_need = plannable_scallop_height(o, delta_p99);
    throw std::invalid_argument(
        short_number(100.0 * double(uncertain) / double(deltas.size()), 6) + " % of the cloud's points are known "
        "too poorly for the scallop height " + short_number(o.scallop_height, 6) + " mm (99 % of them to +-" +
        short_number(delta_p99, 6) + " mm, cloud.denoise's uncertainty or its height field's, the smaller; more than 1 % leaves nearly every "
        "strip over the limit): scallop_height must be at least " +
        short_number(points_need, 6) + " mm for them" + whole_patch_advice(points_need) +
        ", or denoise with more neighbours or scan more finely");
  }
  const WorkEstimate work = estimate_work(cloud, neighbors, map, o, margins(o, delta_median));
  if (work.passes > o.max_passes)
    throw std::invalid_argument(
        "these limits need at least " + short_number(work.passes, 6) + " passes (a side interval of " +
        short_number(work.side_interval, 6) + " mm across a patch " + short_number(work.side_extent, 6) +
        " mm wide; at least " + short_number(std::round(work.points), 6) + " points), more than max_passes " +
        std::to_string(o.max_passes) + ": raise scallop_height or tool_radius, or max_passes if "
        "the time is worth it (planning takes roughly 0.01 to 0.2 s per pass)");
  std::optional<UVInterpolator> interp;
  interp.emplace(cloud.points, cloud.normals, map.uv, domain, o.interpolation_k, planned_uncertainty);
  // The holes: every loop after the outer one, as the polygon of its points' uv.
  std::vector<std::vector<Eigen::Vector2d>> hole_polygons, hole_polygons_xy;
  std::vector<const std::vector<int>*> hole_loops;
  std::vector<std::vector<Eigen::Vector2d>> hole_xy;  // the usable hole loops' points in xy
  if (loops)
    for (std::size_t h = 1; h < loops->loops.size(); ++h) {
      std::vector<Eigen::Vector2d> poly, poly_xy;
      for (int i : loops->loops[h]) {
        if (i < 0 || static_cast<std::size_t>(i) >= cloud.size())
          throw std::invalid_argument("hole loop " + std::to_string(h) + " has point index " +
                                      std::to_string(i) + "; the cloud has " +
                                      std::to_string(cloud.size()) + " points");
        poly.push_back(map.uv[i]);
        poly_xy.push_back(cloud.points[i].head<2>());
      }
      if (poly.size() >= 3) hole_loops.push_back(&loops->loops[h]), hole_xy.push_back(poly_xy);
      hole_polygons.push_back(std::move(poly));
      hole_polygons_xy.push_back(std::move(poly_xy));
    }
  // A planar map's rectangle reaches past the outline: off it is off the patch, and near it the
  // rim pass cuts, as near a hole's edge.
  std::vector<std::vector<Eigen::Vector2d>> outline_uv, outline_xy;
  if (planar) {
    outline_uv.emplace_back(), outline_xy.emplace_back();
    for (std::size_t k = 0; k < map.outer_loop.size() && map.boundary_uv.size() == map.outer_loop.size(); ++k) {
      const int i = map.outer_loop[k];
      if (i < 0 || static_cast<std::size_t>(i) >= cloud.size())
        throw std::invalid_argument("the outer loop has point index " + std::to_string(i) + "; the cloud has " +
                                    std::to_string(cloud.size()) + " points");
      outline_uv.back().push_back(map.boundary_uv[k]);
      outline_xy.back().push_back(cloud.points[i].head<2>());
    }
    if (outline_uv.back().size() < 3)
      throw std::invalid_argument("a planar map needs its outer loop (at least 3 points, with their uv)");
  }
  const OffPatch off_patch(std::move(hole_polygons), std::move(outline_uv));
  const Outline hole_edges(std::move(hole_polygons_xy)), outer_edge(std::move(outline_xy));
  Planner planner(*interp, lifter, model.get(), co, o, off_patch, hole_edges, outer_edge);
  std::optional<Pass> planar_rim;  // a planar map's rim pass, planned first (Planner::set_rim)
  if (planar && o.outline) {
    planar_rim = planner.rim_pass(cloud, map.outer_loop, map.boundary_uv, planned_uncertainty);
    planner.set_rim(*planar_rim);
  }
  std::vector<double> nn;
  for (std::size_t i = 0; i < neighbors.size(); i += std::max<std::size_t>(1, neighbors.size() / 4096))
    if (neighbors.k > 0) nn.push_back(std::sqrt(neighbors.sq_dist(i, 0)));
  std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
  const double cloud_spacing = nn.empty() ? 0 : nn[nn.size() / 2];

  // ---- passes ---------------------------------------------------------------------------------
  std::vector<Pass> passes;
  std::vector<std::vector<VertexInfo>> info;
  passes.push_back(planner.build_pass(0));
  double ds_min = kInf, ds_max = 0, interval_min = kInf, interval_max = 0, scallop_max = 0;
  Eigen::Vector3d scallop_where = Eigen::Vector3d::Zero();
  int shrunk = 0, formula4 = 0, formula3 = 0, strip_checks = 0;
  nlohmann::json warnings = nlohmann::json::array();
  nlohmann::json strips_over = nlohmann::json::array();  // strips no side step kept under h
  double strip_over_worst = 0;
  Eigen::Vector3d strip_over_where = Eigen::Vector3d::Zero();
  const double hlim = planner.h();

  double s = 0;
  std::size_t total_points = passes.back().t.size();
  while (s < co.S) {
    const Pass& A = passes.back();
    info.push_back(planner.infos(A));
    double ds0 = kInf;
    for (const VertexInfo& v : info.back()) {
      if (!std::isfinite(v.ds)) continue;  // concave beyond the ball: reported, not planned for
      ds0 = std::min(ds0, v.ds);
      (v.formula4 ? formula4 : formula3)++;
    }
    // A pass wholly unreachable or, on a planar map, wholly off the patch: the raster's first
    // line, the tangent at the outline's extreme point. From there the first pass inside is
    // stepped as the outline's uncertainty allows (the noisy plane's rim, known to +-0.032 mm,
    // kept 0.073 between the rim pass and a first pass a nominal interval in, where no step
    // kept the strip under the limit and the first try, the nominal one, was kept).
    if (!std::isfinite(ds0)) {
      const Margins at_rim = margins(o, rim_delta);
      ds0 = planar ? side_interval(std::max(at_rim.scallop - at_rim.stock, 0.1 * o.scallop_height * o.safety_factor),
                                   o.tool_radius, 0)
                   : planner.nominal_interval();
    }
    double ds = ds0;
    bool accepted = false;
    Pass B;
    StripCheck chk;
    // The first try is at the formula's step: kept for a strip no step keeps (below).
    Pass B_formula;
    StripCheck chk_formula;
    double ds_prev = 0, scallop_prev = 0;
    int no_gain = 0;  // tries in a row whose smaller step did not lower the scallop
    int above_at_zero = 0;  // tries in a row whose secant stays above the limit at a zero step
    for (int iter = 0; iter < 30; ++iter) {
      const bool last = s + ds >= co.S * (1 - 1e-12);
      const double s_next = last ? co.S : s + ds;
      B = planner.build_pass(s_next);
      chk = planner.check_strip(A, B);
      ++strip_checks;
      ds = s_next - s;
      if (chk.scallop_max <= hlim) {
        accepted = true;
        break;
      }
      if (iter == 0) ++shrunk, B_formula = std::move(B), chk_formula = chk;  // (B is built anew below)
      // A strip that no step down to a 32nd of the formula's keeps under the limit is not kept
      // by creeping the passes over it either (that took up to 30 tries a strip, each a pass
      // built and checked): it is reported, below.
      if (ds <= ds0 / 32) break;
      // where a smaller step leaves as much (a rim or a place the ball cannot reach, not the
      // cusp), shrinking on only creeps: six such tries in a row end it (the scallop may rise
      // for a few tries before it falls: measured on the bundled example's second ring)
      no_gain = iter > 0 && chk.scallop_max >= scallop_prev ? no_gain + 1 : 0;
      if (no_gain >= 6) break;
      // The next step, aimed just under the limit and never less than a quarter of this one.
      // The strip's scallop is the cusp's (~ ds^2) plus margins that do not shrink with the
      // step (the surface's uncertainty, the fit gap): after the first try, the secant through
      // the last two tries finds that step in a try or two where scaling by sqrt(h / scallop)
      // alone took up to 18 (the bundled example: 449 strip checks for 128 passes).
      // Where the secant finds no step (the part that does not shrink with the step is over the
      // limit by itself, or the scallop did not fall), scaling by sqrt(h / scallop) creeps down
      // by 1-5 % a try: from the fourth try on the step is halved instead (the noisy freeform
      // patch at h = 0.1: its 21 strips that no step could keep took 476 of the planner's
      // tries, 30 each, and its plan 14.2 s; 7.9 s so. Halving from the second try shrank a
      // strip of the bundled example whose scallop fell only at its third, and cost it a pass).
      const double target = 0.999 * hlim;
      double next = iter < 3 ? ds * 0.995 * std::sqrt(hlim / chk.scallop_max) : 0.5 * ds;
      if (iter > 0 && chk.scallop_max < scallop_prev && ds < ds_prev) {
        // (in ds^2, in which the cusp's part is linear)
        const double a2 = ds * ds, b2 = ds_prev * ds_prev;
        const double secant2 = a2 - (chk.scallop_max - target) * (b2 - a2) / (scallop_prev - chk.scallop_max);
        if (std::isfinite(secant2) && secant2 > 0) next = std::sqrt(secant2);
        // Two secants in a row through tries whose scallop fell with the step stay over the
        // limit at a zero step: the part that does not shrink with the step is over it by
        // itself, and no step keeps this strip (see below). Halving on took the noisy freeform
        // patch's 20 such strips 9 tries each (h = 0.1: 578 strip checks for 214 passes, the
        // plan 7.6 s; 512 and 6.0 s so, two more of its strips given up, its certificate
        // passing as before); the clean catalog's programs and the bundled example's are the
        // same but the 3 mm crest's (whose certificate's bounds fell: scallop 0.138 -> 0.126).
        above_at_zero = std::isfinite(secant2) && secant2 > 0 ? 0 : above_at_zero + 1;
        if (above_at_zero >= 2) break;
      } else {
        above_at_zero = 0;
      }
      ds_prev = ds, scallop_prev = chk.scallop_max;
      ds = std::clamp(next, 0.25 * ds, 0.995 * ds);
    }
    if (!accepted) {
      // No step keeps the limit here (a concave place the ball cannot reach, a kink): take the
      // formula's step, the first try, rather than creep on with vanishing ones, and say so.
      B = std::move(B_formula);
      chk = chk_formula;
      const bool uncut = chk.scallop_max >= kUncut;
      strips_over.push_back({{"s_from", s}, {"s_to", B.s}, {"scallop", uncut ? nlohmann::json() : nlohmann::json(chk.scallop_max)},
                             {"uncut", uncut}});
      if (chk.scallop_max > strip_over_worst) strip_over_worst = chk.scallop_max, strip_over_where = chk.where;
    }
    ds_min = std::min(ds_min, B.s - s);
    ds_max = std::max(ds_max, B.s - s);
    interval_min = std::min(interval_min, chk.interval_min);
    interval_max = std::max(interval_max, chk.interval_max);
    if (chk.scallop_max > scallop_max) scallop_max = chk.scallop_max, scallop_where = chk.where;
    s = B.s;
    total_points += B.t.size();
    passes.push_back(std::move(B));
    if (passes.size() > o.max_passes || total_points > o.max_points)
      throw std::invalid_argument(
          "the path needs more than " +
          (passes.size() > o.max_passes ? std::to_string(o.max_passes) + " passes"
                                        : std::to_string(o.max_points) + " points") +
          " (stopped at s = " + short_number(s, 6) + " of " + short_number(co.S, 6) + ", side steps down to " +
          short_number(ds_min, 6) + "): the UV map is degenerate or the cloud too noisy for these limits "
          "(check the map report, smooth or clean the cloud, or raise scallop_height)");
    if (o.progress) o.progress(s / co.S, "pass " + std::to_string(passes.size()));
  }
  info.push_back(planner.infos(passes.back()));

  // ---- outline --------------------------------------------------------------------------------
  // Zig-zag passes end on the rectangle's edges v = 0 and v = H, and both patterns' outermost
  // passes follow the interpolant, which rounds the outline's corners off: between two pass
  // ends the rim is cut only by the balls' ends, and at a corner not at all. The rim pass runs
  // through the outline's own points (Planner::rim_pass).
  std::vector<Pass> outline;
  const std::size_t n_outer = map.outer_loop.size();
  bool outer_usable = n_outer >= 3 && map.boundary_uv.size() == n_outer;
  for (std::size_t k = 0; outer_usable && k < n_outer; ++k)
    outer_usable = map.outer_loop[k] >= 0 && static_cast<std::size_t>(map.outer_loop[k]) < cloud.size();
  if (o.outline) {
    if (planar_rim) outline.push_back(std::move(*planar_rim));
    else if (outer_usable) outline.push_back(planner.rim_pass(cloud, map.outer_loop, map.boundary_uv, planned_uncertainty));
    else
      warnings.push_back("the map has no usable outer loop (" + std::to_string(n_outer) +
                         " points): no rim pass, the outline is cut only by the passes' ends");
  }
  std::vector<std::vector<Eigen::Vector2d>> hole_uv;
  for (const std::vector<int>* loop : hole_loops) {  // and around every hole
    hole_uv.emplace_back();
    for (int i : *loop) hole_uv.back().push_back(map.uv[i]);
    outline.push_back(planner.rim_pass(cloud, *loop, hole_uv.back(), planned_uncertainty));
  }
  // ---- the band beyond the outline ------------------------------------------------------------
  // A cloud's outer loop runs through its outermost points, and the real outline lies beyond it
  // by the sampling's gaps: on the catalog's 50 000-point clouds up to 0.94 mm (1.35 mm at the
  // freeform's spike, 2.7 spacings; bench/outline_gap.py), where the rim pass alone left the
  // whole patch up to 4 h. Closed passes offset from the outer loop, away from the patch, cut
  // that band: `rim_band` along the surface in steps of at most 0.55 of the nominal side
  // interval (a wider step left the steep canopy rim's scallop over h between them).
  // A hole's edge lies beyond the points around it the same way (a waves patch with two holes,
  // 50 000 points: a gap of 1.15 mm at a hole's edge, where both programs left 0.12 mm and the
  // certificate, measuring up to the hole's loop, passed the contour one): its band is cut into
  // the hole, no farther than half the hole's radius (its area's circle), so that a small hole's
  // offsets do not cross over to its far side.
  std::vector<Pass> band;
  const double rim_band = o.rim_band >= 0 ? o.rim_band : rim_band_width(model->spacing());
  const double band_step = 0.55 * planner.nominal_interval();
  if (o.outline && outer_usable && rim_band > 0) {
    const auto band_steps = static_cast<std::size_t>(std::ceil(rim_band / band_step - 1e-9));
    for (std::size_t k = 1; k <= band_steps; ++k)
      band.push_back(planner.rim_pass(cloud, map.outer_loop, map.boundary_uv, planned_uncertainty,
                                      rim_band * double(k) / double(band_steps)));
  }
  for (std::size_t h = 0; h < hole_loops.size() && o.outline && rim_band > 0; ++h) {
    const std::vector<int>* loop = hole_loops[h];
    const double width = std::min(rim_band, 0.5 * std::sqrt(0.5 * std::abs(twice_signed_area(hole_xy[h])) / M_PI));
    const auto band_steps = static_cast<std::size_t>(std::ceil(width / band_step - 1e-9));
    for (std::size_t k = 1; k <= band_steps; ++k)
      band.push_back(planner.rim_pass(cloud, *loop, hole_uv[h], planned_uncertainty,
                                      width * double(k) / double(band_steps), /*hole=*/true));
  }

  // ---- concave places the ball cannot reach -----------------------------------------------------
  std::vector<Eigen::Vector3d> concave_pts;
  std::vector<double> concave_r;
  for (std::size_t i = 0; i < passes.size(); ++i)
    for (std::size_t k = 0; k < passes[i].p.size(); ++k)
      if (!passes[i].off[k] && info[i][k].unreachable) {
        concave_pts.push_back(passes[i].p[k]);
        concave_r.push_back(-1.0 / info[i][k].kappa_min);
      }
  const double link = 1.01 * std::max(o.max_segment, 2 * std::max(interval_max, planner.nominal_interval()));

  // ---- output ---------------------------------------------------------------------------------
  IsoparametricResult res;
  Toolpath& tp = res.toolpath;
  tp.tool_radius = o.tool_radius;
  tp.scallop_height = o.scallop_height;
  tp.chord_error = o.chord_error;
  tp.pattern = o.pattern;
  std::size_t points = 0, lifted = 0;
  double length = 0, lift_max = 0;
  // One planned pass into the output (cut backwards when `reverse`), counted in the report.
  // A pass crossing a hole becomes one output pass per piece on the patch (the tool lifts
  // between them); a closed pass over a hole starts after it, so its pieces are not split at t = 0.
  auto emit = [&](const Pass& P, const Coords& c, bool reverse) {
    const std::size_t n = P.p.size();
    std::vector<std::size_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = k;
    const auto first_off = std::find(P.off.begin(), P.off.end(), 1);
    if (P.closed && n > 2 && first_off != P.off.end()) {
      const std::size_t f = first_off - P.off.begin();
      order.clear();
      for (std::size_t k = f; k + 1 < n; ++k) order.push_back(k);
      for (std::size_t k = 0; k <= f; ++k) order.push_back(k);
    }
    if (reverse) std::reverse(order.begin(), order.end());
    ToolpathPass out;
    auto flush = [&]() {
      if (out.contact.size() >= 2 || (out.contact.size() == 1 && n == 1)) {
        points += out.contact.size();
        tp.passes.push_back(std::move(out));
      }
      out = ToolpathPass{};
    };
    for (std::size_t k : order) {
      if (P.off[k]) {
        flush();
        continue;
      }
      lift_max = std::max(lift_max, P.lift[k]);
      if (P.lift[k] > 1e-3 * o.chord_error) ++lifted;
      if (!out.contact.empty()) length += (P.p[k] - out.contact.back()).norm();
      out.contact.push_back(P.p[k]);
      out.normal.push_back(P.n[k]);
      out.uv.push_back(P.uv.empty() ? c.uv(P.s, P.t[k]) : P.uv[k]);
    }
    flush();
  };

  // The contour pattern cuts the rim first and goes inwards; the zig-zag cuts it last.
  if (co.polar)
    for (const auto* group : {&outline, &band})
      for (const Pass& P : *group) emit(P, co, false);
  for (std::size_t i = 0; i < passes.size(); ++i)
    emit(passes[i], co, o.pattern == "zigzag" && i % 2 == 1);  // zig-zag: alternate directions
  if (!co.polar)
    for (const auto* group : {&outline, &band})
      for (const Pass& P : *group) emit(P, co, false);
  // Where a warning's place lies beyond the cloud's outer loop, the passes there run over the
  // band the real outline may reach into, over a surface extrapolated from the rim, and the
  // certificate measures up to the loop: said, so that a place off the part is not taken for one
  // on it (the bundled example's contour program warned of a strip 2.4 mm beyond its corner).
  std::optional<Outline> outer_outline;  // built only when a warning asks
  auto place = [&](const Eigen::Vector3d& p) {
    if (!outer_outline) {
      std::vector<std::vector<Eigen::Vector2d>> loops(outer_usable ? 1 : 0);
      if (outer_usable)
        for (int i : map.outer_loop) loops[0].push_back(cloud.points[i].head<2>());
      outer_outline.emplace(std::move(loops));
    }
    std::string text = "x " + short_number(p.x(), 6) + ", y " + short_number(p.y(), 6);
    const double beyond = outer_outline->empty() ? 0.0 : outer_outline->beyond(p.head<2>());
    if (beyond > 0)
      text += ", " + short_number(beyond, 6) + " mm beyond the cloud's outline, where the surface is extrapolated and the "
              "certificate does not measure";
    return text;
  };
  if (!strips_over.empty())
    warnings.push_back(std::to_string(strips_over.size()) + " of " +
                       std::to_string(passes.size() - 1) +
                       " strips between passes leave more than the scallop limit at every side "
                       "step tried (" +
                       (strip_over_worst >= kUncut ? std::string("uncut places, which neither pass's ball reaches, one near ")
                                                   : "a scallop of up to " + short_number(strip_over_worst, 6) + " mm, near ") +
                       place(strip_over_where) +
                       "; strips_over_limit_at lists them): a concave place the ball cannot "
                       "reach, a kink, or a surface too uncertain there");
  if (planner.forward_floor_hits > 0)
    warnings.push_back(std::to_string(planner.forward_floor_hits) +
                       " forward steps reached the smallest step with the chord still too far "
                       "off (a kink in the surface or the map?), the first near " +
                       place(planner.forward_floor_at));
  if (rim_height > o.scallop_height)
    warnings.push_back("the cloud's outline is known only to +-" + short_number(rim_delta, 6) +
                       " mm (its points' fits are one-sided, and between them the surface is extrapolated): "
                       "the certificate's whole-patch bound there needs scallop_height " + short_number(rim_height, 6) +
                       " mm or more, and may fail at the outline while the interior holds");
  if (uncertain > 0)
    warnings.push_back(std::to_string(uncertain) + " cloud points (" +
                       short_number(100.0 * uncertain / cloud.size(), 6) + " %) are known only to +-" +
                       short_number(delta_max, 6) + " mm at worst: too little of the scallop height is left "
                       "there, so the side step is cut to a tenth and the limit may not hold");
  if (!concave_pts.empty())
    warnings.push_back(std::to_string(concave_pts.size()) +
                       " path points lie where the surface is concave with a radius below the "
                       "tool radius: the ball cannot reach there without gouging");

  auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  res.report = {
      {"pattern", o.pattern},
      {"tool_radius", o.tool_radius},
      {"scallop_height", o.scallop_height},
      {"chord_error", o.chord_error},
      {"planned_scallop_height", hlim},
      {"surface_error", {{"option", o.surface_error},
                         {"median", delta_median},
                         {"max", delta_max},
                         {"stock_at_median", margins(o, delta_median).stock},
                         {"stock_at_max", margins(o, delta_max).stock},
                         {"too_uncertain_points", uncertain},
                         {"fit_gap_max", planner.fit_gap_max()}}},
      {"passes", passes.size()},
      {"outline_passes", outline.size()},
      {"rim_band", {{"width", rim_band}, {"passes", band.size()}}},
      {"estimate", {{"passes", work.passes}, {"points_at_least", work.points},
                    {"side_interval", work.side_interval}, {"side_extent", work.side_extent},
                    {"area", work.area}}},
      {"points", points},
      {"contact_length", length},
      {"cloud_spacing", cloud_spacing},
      {"side_step", {{"min", ds_min}, {"max", ds_max}}},
      {"side_interval", {{"min", interval_min}, {"max", interval_max},
                         {"nominal_plane", std::sqrt(8 * o.tool_radius * hlim)}}},
      {"forward_interval", {{"min", planner.forward_min}, {"max", planner.forward_max}}},
      {"side_formula", {{"formula3_points", formula3}, {"formula4_points", formula4},
                        {"conformal_tolerance_deg", o.conformal_tolerance}}},
      {"steps_shrunk_by_check", shrunk},
      {"strip_checks", strip_checks},
      {"outline_uncertainty", rim_delta},
      {"outline_scallop_height", rim_height},
      {"strips_over_limit", strips_over.size()},
      {"strips_over_limit_at", strips_over},
      {"predicted", {{"scallop_max", scallop_max}, {"scallop_max_at", vec(scallop_where)},
                     {"chord_overcut_max", planner.chord_overcut_max},
                     {"chord_undercut_max", planner.chord_undercut_max}}},
      {"ball_lifted", {{"points", lifted}, {"max", lift_max}}},
      {"concave_regions", concave_regions(concave_pts, concave_r, link)},
      {"warnings", warnings},
  };
  if (passes.size() == 1 || !std::isfinite(ds_min)) {
    res.report["side_step"] = {{"min", nullptr}, {"max", nullptr}};
    res.report["side_interval"]["min"] = nullptr;
  }
  return res;
}

}  // namespace scallop
