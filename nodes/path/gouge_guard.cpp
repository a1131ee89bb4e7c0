#include "nodes/path/gouge_guard.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nodes/cloud/denoise.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/obstacle_points.h"
#include "nodes/geom/point_text.h"
#include "nodes/path/step_size.h"

namespace scallop {

struct BallClearance::Impl {
  const HeightFieldModel& surface;
  const std::vector<Eigen::Vector3d>& points;
  double r;
  const Outline* outline;
  double rim_band = 0;  // mm beyond the outline's outer loop still on the surface
  PointsAdaptor<Eigen::Vector3d> adaptor{points};
  KdTree<Eigen::Vector3d, 2> tree{2, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};   // by xy
  // in 3-D: the height field's own when it is over these points (built once for both), else ours
  std::unique_ptr<KdTree<Eigen::Vector3d, 3>> own_tree3;
  const KdTree<Eigen::Vector3d, 3>* tree3 = nullptr;
  // The band the ball must clear, sampled above each cloud point (surface_band.h): computed
  // here when not given. Two tiers of it, so that a few very uncertain samples (an extrapolated
  // rim, a crest) do not widen every search.
  SurfaceBand computed;
  SurfaceBandView band;
  struct BandTier {
    std::vector<std::uint32_t> index;  // into band
    double uncertainty_max = 0;
    SubsetAdaptor<Eigen::Vector3d> adaptor;
    KdSubsetTree<Eigen::Vector3d, 3> tree{3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};
    explicit BandTier(const std::vector<Eigen::Vector3d>& at) : adaptor{at, index} {}
  };
  BandTier tier[2]{BandTier(band.at), BandTier(band.at)};
  // The points not machined as given (empty when none were), and those of them the ball keeps
  // clear of (obstacle_points: apart from the patch by 3 spacings), by xy and in 3-D.
  const std::vector<Eigen::Vector3d> no_points;
  const std::vector<Eigen::Vector3d>& given_left_out;
  std::vector<Eigen::Vector3d> left_out;
  PointsAdaptor<Eigen::Vector3d> left_out_adaptor{left_out};
  KdTree<Eigen::Vector3d, 2> left_out_xy{2, left_out_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};
  KdTree<Eigen::Vector3d, 3> left_out_3d{3, left_out_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)};
  Impl(const HeightFieldModel& s, const std::vector<Eigen::Vector3d>& p, double radius, const Outline* o,
       const SurfaceBandView* given, const std::vector<Eigen::Vector3d>* left)
      : surface(s),
        points(p),
        r(radius),
        outline(o),
        computed(given ? SurfaceBand{} : surface_band(s, p)),
        band(given ? *given : SurfaceBandView{computed.at, computed.uncertainty}),
        given_left_out(left ? *left : no_points) {
    if (band.at.size() != band.uncertainty.size())
      throw std::invalid_argument("the surface band has " + std::to_string(band.at.size()) + " places but " +
                                  std::to_string(band.uncertainty.size()) + " uncertainties");
    // the upper tier: the most uncertain 1 %
    double split = INFINITY;
    if (!band.uncertainty.empty()) {
      std::vector<double> sorted = band.uncertainty;
      const std::size_t cut = sorted.size() - sorted.size() / 100 - 1;
      std::nth_element(sorted.begin(), sorted.begin() + cut, sorted.end());
      split = sorted[cut];
    }
    for (std::size_t i = 0; i < band.at.size(); ++i) {
      if (!band.at[i].allFinite() || !std::isfinite(band.uncertainty[i])) continue;
      BandTier& t = tier[band.uncertainty[i] > split ? 1 : 0];
      t.index.push_back(static_cast<std::uint32_t>(i));
      t.uncertainty_max = std::max(t.uncertainty_max, band.uncertainty[i]);
    }
    tbb::parallel_invoke([&] { tree.buildIndex(); },
                         [&] {
                           if (&points == &surface.points()) {
                             tree3 = &surface.tree3d();
                           } else {
                             own_tree3 = std::make_unique<KdTree<Eigen::Vector3d, 3>>(
                                 3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
                             own_tree3->buildIndex();
                             tree3 = own_tree3.get();
                           }
                         },
                         [&] { if (!tier[0].index.empty()) tier[0].tree.buildIndex(); },
                         [&] { if (!tier[1].index.empty()) tier[1].tree.buildIndex(); });
    if (given_left_out.empty()) return;
    left_out = obstacle_points(given_left_out, surface);
    if (left_out.empty()) return;
    tbb::parallel_invoke([&] { left_out_xy.buildIndex(); }, [&] { left_out_3d.buildIndex(); });
  }
  // Whether q (xy) lies off the patch over what was left out: a left-out point nearer than any
  // of the cloud's, cloud_d2(q) away (the field beyond the cloud's edge would be extrapolated
  // over a wall there). The cloud's nearest point is searched for only where it can decide.
  template <class CloudD2>
  bool over_left_out(const Eigen::Vector2d& q, const CloudD2& cloud_d2) const {
    if (left_out.empty() || (outline && outline->beyond(q) <= 0)) return false;
    std::uint32_t j;
    double d2;
    nanoflann::KNNResultSet<double, std::uint32_t> one(1);
    one.init(&j, &d2);
    const double at[3] = {q.x(), q.y(), 0};
    left_out_xy.findNeighbors(one, at, nanoflann::SearchParams(32, 0, false));
    return d2 < cloud_d2(q);
  }
};

namespace {

constexpr double kPi = 3.14159265358979323846;

// A nanoflann result set: the point nearest a centre c among those whose xy lies within r of
// c's (as a radius search over the xy tree takes them), and nearer than a first bound.
struct NearestInDisc {
  const std::vector<Eigen::Vector3d>& points;
  Eigen::Vector2d centre_xy;
  double r2;
  double best2;  // squared distance of the nearest found, at first the bound squared
  std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
  void init() {}
  std::size_t size() const { return best == std::numeric_limits<std::uint32_t>::max() ? 0 : 1; }
  bool full() const { return true; }
  bool addPoint(double d2, std::uint32_t i) {
    if (d2 < best2 && (points[i].head<2>() - centre_xy).squaredNorm() < r2) best2 = d2, best = i;
    return true;
  }
  double worstDist() const { return best2; }
};

// A nanoflann result set over one band tier: how far a ball at c reaches into the band over the
// samples near it (a sample's uncertainty less its distance from c beyond r), the deepest, and
// the upward part of the direction from that sample to c (how fast lifting the ball takes it
// out). Unlike the foot point it sees every place near the ball: on a crest the fit has
// flattened, the foot search settles on one flank while the ball passes within reach of the top,
// where the fit's misfit, and so its uncertainty, is largest (a 1 mm crest's 50 000-point cloud:
// the ball 0.014 mm from a place of uncertainty 0.35 mm whose foot point on the flank asked for
// 0.002).
struct DeepestIntoBand {
  const Eigen::Vector3d& c;
  const SurfaceBandView& band;
  const std::vector<std::uint32_t>& tier;  // the tree's positions -> the band's indices
  double r, radius2;
  double deepest = -INFINITY, up = 1;
  void init() {}
  std::size_t size() const { return 0; }
  bool full() const { return true; }
  bool addPoint(double d2, std::uint32_t k) {
    if (!(d2 < radius2)) return true;
    const std::uint32_t i = tier[k];
    const double d = std::sqrt(d2), reach = band.uncertainty[i] - (d - r);
    if (reach > deepest) deepest = reach, up = d > 0 ? (c.z() - band.at[i].z()) / d : 1.0;
    return true;
  }
  double worstDist() const { return radius2; }
};

}  // namespace

BallClearance::BallClearance(const HeightFieldModel& surface, const std::vector<Eigen::Vector3d>& points,
                             double r, const Outline* outline, const SurfaceBandView* band, double rim_band,
                             const std::vector<Eigen::Vector3d>* left_out)
    : impl_(nullptr) {
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (points.empty()) throw std::invalid_argument("the cloud has no points");
  impl_ = new Impl(surface, points, r, outline, band, left_out);
  impl_->rim_band = rim_band;
}

BallClearance::~BallClearance() { delete impl_; }

double BallClearance::spacing() const { return impl_->surface.spacing(); }
const std::vector<Eigen::Vector3d>& BallClearance::points() const { return impl_->points; }
const Outline* BallClearance::outline() const { return impl_->outline; }
const std::vector<Eigen::Vector3d>& BallClearance::left_out() const { return impl_->given_left_out; }
const KdTree<Eigen::Vector3d, 2>& BallClearance::xy_tree() const { return impl_->tree; }

BallClearance::Result BallClearance::operator()(const Eigen::Vector3d& c, const Eigen::Vector3d& hint) const {
  const double r = impl_->r;
  Result res;
  // Foot point of c on the height field (at most a ball radius per step: a poor start must not
  // throw the search off the patch).
  Eigen::Vector2d s = hint.head<2>();
  double z = 0;
  Eigen::Vector3d n;
  const bool found = impl_->surface.foot_point(c, hint.head<2>(), r, s);
  // On the patch, or in the band where the part's edge lies: within a cloud spacing of its
  // outermost points (they sit about half a spacing inside the edge), or up to two spacings
  // away in a gap the sample left between the points of a rim (no farther out than half a
  // spacing past them). The field's extrapolation there, with its grown uncertainty, is the
  // best estimate of the part.
  // Given the outline, everywhere inside it as well (no point search needed there), and in the
  // rim band beyond it.
  const double sp = impl_->surface.spacing();
  auto nearest_point_d2 = [&](const Eigen::Vector2d& q) {
    std::uint32_t j;
    double d2;
    nanoflann::KNNResultSet<double, std::uint32_t> one(1);
    one.init(&j, &d2);
    const double at[3] = {q.x(), q.y(), 0};
    impl_->tree.findNeighbors(one, at, nanoflann::SearchParams(32, 0, false));
    return d2;
  };
  auto in_band = [&](const Eigen::Vector2d& q) {
    if (impl_->over_left_out(q, nearest_point_d2)) return false;
    if (impl_->outline) {
      // on the patch (0), or off it (beyond the outer loop or in a hole) within the rim band
      if (impl_->outline->beyond(q) <= std::max(impl_->rim_band, 0.0)) return true;
    }
    const double d2 = nearest_point_d2(q);
    return d2 <= sp * sp || (d2 <= 4 * sp * sp && impl_->surface.reach_beyond(q.x(), q.y()) <= 0.5 * sp);
  };
  auto near_cloud = [&] {
    // (the uncertainty does not depend on force: the first eval below has set it)
    return in_band(s) && impl_->surface.eval(s.x(), s.y(), z, n, /*force=*/true);
  };
  if (found && (impl_->surface.eval(s.x(), s.y(), z, n, /*force=*/false, &res.uncertainty) || near_cloud()) &&
      !impl_->over_left_out(s, nearest_point_d2)) {
    res.on_surface = true;
    res.foot = Eigen::Vector3d(s.x(), s.y(), z);
    res.normal = n;
    const Eigen::Vector3d d = c - res.foot;
    res.clearance = (d.dot(n) >= 0 ? d.norm() : -d.norm()) - r;
  }
  // Beyond the cloud's edge (the foot farther than half a spacing from the nearest point) the
  // field's uncertainty grows with the distance from the points faster than the ball's distance
  // from the surface does: a place a few tenths of a mm outward is reached deeper than the foot
  // (the noisy dome's contour program: 0.0107 into the band 0.19 mm beyond the foot, where the
  // uncertainty was 0.048 and at the foot 0.034). Places around the foot half a spacing and one
  // spacing away, on the patch as the certificate counts it, are checked too. (Rings at 2, 4 and
  // 8 spacings as well took the bundled example's guard from 1.6 to 2.9 s and never came within
  // 0.02 mm of deciding on it or on the noisy dome, canopy and freeform patch: the same programs;
  // they lifted balls only beyond the clean 3 mm crest's rim, where the certificate does not look.)
  // Where the uncertainty cannot grow within a spacing (inside the edge, the fit following its
  // points: there it is the mean of the nearest points' own) the ring is not looked at: on the
  // bundled example and 10 catalog and crest clouds, clean and noisy, the same programs, and the
  // guard 0.61 to 1.0 times as long (the example 1.19 -> 0.92 s). With the ring only beyond the
  // edge, one ball of the clean freeform patch and several of the 3 mm crest were lifted less
  // (the crest's gouge bound 0.04924 -> 0.04979); with a misfit floor of 1e-3 mm instead of the
  // points' least uncertainty, some of the crest's.
  // Tried (stop 80): a ring a tenth and a quarter of a spacing around every foot whose fit
  // misfits by over 5e-4 mm (3 times its misfit), where the quadratic's bound saw-tooths across a
  // crest (0.0013 -> 0.0025 -> 0.0013 mm within 0.1 mm) and the certificate, sampling between
  // the guard's places, finds the ball deeper in the band than the guard did. The catalog's clean
  // 3 mm crest's zig-zag certificate then passed (gouge bound 0.01047 -> 0.00974, verify.py the
  // same), the 5 mm crest's of the tests too (0.0103 -> 0.0097), every smooth catalog row the
  // same; but on the tests' sparser 3 mm crest of slope 0.3 (5000 points) the balls it lifted,
  // which the planner had not planned for, took the exact whole-patch scallop 0.0492 -> 0.0509
  // (0.0527 with the ring in the points' gaps too, 0.0532 beyond the edge as well), over h, and
  // the 1 mm crest's 0.0827 -> 0.0866. Not kept.
  // The band sampled above the cloud's points, every sample within reach.
  double samples_reach = -INFINITY, samples_up = 1;
  for (const auto& tier : impl_->tier) {
    if (tier.index.empty()) continue;
    const double radius = r + tier.uncertainty_max;
    DeepestIntoBand deepest{c, impl_->band, tier.index, r, radius * radius};
    tier.tree.findNeighbors(deepest, c.data(), nanoflann::SearchParams(32, 0, false));
    if (deepest.deepest > samples_reach) samples_reach = deepest.deepest, samples_up = deepest.up;
  }
  if (res.on_surface && nearest_point_d2(s) > 0.25 * sp * sp &&
      impl_->surface.uncertainty_may_grow(s.x(), s.y(), kUncertaintyFloor)) {
    // A place of the ring changes the result only where it reaches deeper than the band's
    // samples and the foot (whose reach can only grow below, as the witness lowers the
    // clearance): whether it lies in the band and how much its uncertainty grows beyond the
    // edge (the 64 nearest points' angular gap) are asked only where it could, its uncertainty
    // grown the most it can. The same programs and reports, the guard 1.2 to 2 times as quick
    // (the bundled example 0.90 -> 0.44 s; the catalog's noisy plane and dome, clean freeform,
    // canopy and 1 mm crest, both patterns; stop 88).
    const double deeper_than = std::max(samples_reach, res.foot_reach());
    for (double rho : {0.5, 1.0})
      for (int k = 0; k < 8; ++k) {
        const double a = k * (kPi / 4);
        const Eigen::Vector2d q = s + rho * sp * Eigen::Vector2d(std::cos(a), std::sin(a));
        double zq, before_growth, growth_max;
        Eigen::Vector3d nq;
        if (!impl_->surface.eval_before_growth(q.x(), q.y(), zq, nq, before_growth, growth_max)) continue;
        const Eigen::Vector3d to_c = c - Eigen::Vector3d(q.x(), q.y(), zq);
        const double d = to_c.norm();
        if (before_growth * growth_max - (d - r) < deeper_than || !in_band(q)) continue;
        const double reach = before_growth * impl_->surface.edge_growth(q.x(), q.y()) - (d - r);
        if (reach > res.band_reach) res.band_reach = reach, res.band_up = d > 0 ? to_c.z() / d : 1.0;
      }
  }
  if (samples_reach > res.band_reach) res.band_reach = samples_reach, res.band_up = samples_up;
  // The points not machined near the centre: the ball keeps clear of them (obstacle_keep_off).
  if (!impl_->left_out.empty()) {
    const double reach_r = obstacle_keep_off(r, sp);
    std::vector<std::pair<std::uint32_t, double>> near;
    impl_->left_out_3d.radiusSearch(c.data(), reach_r * reach_r, near, nanoflann::SearchParams(32, 0, false));
    for (const auto& [j, d2] : near) {
      const double d = std::sqrt(d2), reach = reach_r - d;
      if (reach > res.band_reach) {
        res.band_reach = reach, res.band_up = d > 0 ? (c.z() - impl_->left_out[j].z()) / d : 1.0;
        res.left_out_deepest = true, res.left_out_at = impl_->left_out[j];
      }
    }
  }
  // The cloud's own points within r of the centre in xy: a witness that needs no fit. Only those
  // nearer the centre than r + the clearance found can lower it, so where one was found the
  // nearest such point is looked for in 3-D below that bound (a million-point cloud has thousands
  // in the disc, a few in the ball; the same least value).
  if (std::isfinite(res.clearance)) {
    const double cap = r + res.clearance;
    if (cap > 0) {
      NearestInDisc nearest{impl_->points, c.head<2>(), r * r, cap * cap};
      impl_->tree3->findNeighbors(nearest, c.data(), nanoflann::SearchParams(32, 0, false));
      if (nearest.size()) res.clearance = std::min(res.clearance, (c - impl_->points[nearest.best]).norm() - r);
    }
    return res;
  }
  std::vector<std::pair<std::uint32_t, double>> hits;
  impl_->tree.radiusSearch(c.data(), r * r, hits, nanoflann::SearchParams(32, 0, false));
  for (const auto& h : hits) res.clearance = std::min(res.clearance, (c - impl_->points[h.first]).norm() - r);
  return res;
}

namespace {

constexpr double kProbeStep = 0.5;  // mm between the points checked along a long move
constexpr double kMaxLiftRadii = 3;  // a lift higher than this many tool radii fails the node

struct Sample {
  Eigen::Vector3d contact, normal;
  Eigen::Vector2d uv;
};

struct Tally {
  std::size_t positions = 0, moves = 0, lifted = 0, inserted = 0, unresolved = 0;
  std::size_t raised_moves = 0;  // moves raised whole (both ends) after their halvings
  std::size_t pushed = 0;        // planned positions moved sideways off what the trim left out
  double deepest = 0;  // deepest cut-in found (mm)
  Eigen::Vector3d deepest_at = Eigen::Vector3d::Zero();
  double highest_lift = 0;
  Eigen::Vector3d highest_lift_at = Eigen::Vector3d::Zero();
  Eigen::Vector3d highest_lift_from = Eigen::Vector3d::Zero();  // the planned ball centre there
  void add(const Tally& o) {
    positions += o.positions, moves += o.moves, lifted += o.lifted, inserted += o.inserted;
    unresolved += o.unresolved, raised_moves += o.raised_moves, pushed += o.pushed;
    if (o.deepest > deepest) deepest = o.deepest, deepest_at = o.deepest_at;
    if (o.highest_lift > highest_lift)
      highest_lift = o.highest_lift, highest_lift_at = o.highest_lift_at, highest_lift_from = o.highest_lift_from;
  }
};

class PassGuard {
 public:
  // tol > 0: how far a position may reach in; <= 0: what the planner meant it to reach (the
  // chord budget's reach for the surface's uncertainty there) plus e/4 for the two fits' difference.
  PassGuard(const BallClearance& clearance, double r, double e, double tol, double chord_tol, int max_splits)
      : clearance_(clearance), r_(r), e_(e), tol_(tol), chord_tol_(chord_tol), max_splits_(max_splits) {}

  double position_tolerance(const BallClearance::Result& x) const {
    if (tol_ > 0) return tol_;
    return 0.25 * e_ + (x.on_surface ? chord_budget(e_, x.uncertainty).reach : 0.0);
  }
  // How far a move may reach in between its positions: chord_tolerance when given, else the
  // gouge budget for the surface's uncertainty where the move reaches deepest (step_size.h).
  double move_tolerance(const BallClearance::Result& x) const {
    if (chord_tol_ > 0) return chord_tol_;
    return gouge_budget(e_, x.on_surface ? x.uncertainty : 0.0);
  }

  // How fast raising the ball takes it out of the band where `x` measured it: the upward part of
  // the direction from the deepest witness (raising the centre by dz moves it away from a
  // surface with normal n by dz * n_z), no less than 0.2.
  static double rise_rate(const BallClearance::Result& x) {
    return x.band_is_deepest() ? std::max(x.band_up, 0.2) : x.on_surface ? std::max(x.normal.z(), 0.2) : 0.5;
  }

  // How far into the band a lifted ball is left: none, or where the tolerance is a clearance
  // (the gouge budget below 0 where the surface is known worse than 6 e: beyond the cloud's
  // edge, where its uncertainty grows), half as much again clear of it. Lifted only to that
  // tolerance, the moves beside it reached in by it, were halved three times, and were raised
  // by steps that stopped halfway to it (the noisy plane's band passes: 948 moves, 899 left
  // unresolved, 4 of the guard's 4.6 s).
  static double lift_target(double tolerance) { return std::min(0.0, 1.5 * tolerance); }

  // A point inserted into a move is left reaching into the band by 3/4 of the move's tolerance
  // (where that is no clearance): what the move's other balls may. Its halves' middles then
  // reach in by about 3/8 of it plus a quarter of the move's sag. Lifted to touch the band, a
  // point inserted into a chord that sagged just over the tolerance rose by the whole sag: on
  // the clean canopy 0.012 mm, and the cusp beside it by 0.006 mm more than planned.
  static double inserted_target(double tolerance) { return tolerance > 0 ? 0.75 * tolerance : lift_target(tolerance); }

  // Lifts the sample's ball when it reaches into that band more than position_tolerance (a
  // planned position; then until it only touches it, lift_target) or inserted_target (a point
  // inserted into a move; then to that); true when it was lifted.
  bool lift_if_needed(Sample& s, bool planned_position, Tally& t) const {
    Eigen::Vector3d c = s.contact + r_ * s.normal;
    auto res = clearance_(c, s.contact);
    auto tolerance = [&] { return planned_position ? position_tolerance(res) : move_tolerance(res); };
    auto target = [&] { return planned_position ? lift_target(tolerance()) : inserted_target(tolerance()); };
    // lifted when it reaches past its tolerance, or an inserted point past its target (in a
    // clearance, as a planned position, past the tolerance)
    auto threshold = [&] {
      const double tol = tolerance();
      return planned_position || tol <= 0 ? tol : inserted_target(tol);
    };
    if (!(res.reach() > threshold())) return false;
    if (res.reach() > t.deepest) t.deepest = res.reach(), t.deepest_at = s.contact;
    if (planned_position && res.band_is_deepest() && res.left_out_deepest && push_off_left_out(s, res)) {
      ++t.pushed;
      return true;
    }
    const Eigen::Vector3d planned = c;
    const double z0 = c.z();
    double z_below = c.z();  // the highest centre found still too deep
    for (int it = 0; it < 8 && res.reach() > target() + 1e-6; ++it) {
      z_below = c.z();
      c.z() += (res.reach() - target()) / rise_rate(res);
      res = clearance_(c, res.on_surface ? res.foot : s.contact);
    }
    if (res.reach() < target() - 0.1 * e_ && c.z() - z_below > 0.1 * e_) {
      // The last step overshot (the witness left the ball slower than its rate said: beside a
      // wall, whose points lie level with the centre, it was taken as 0.2 and the first step
      // lifted 5 times the reach; a floor beside a 10 mm wall was refused for a lift of 40.8 mm
      // where 9.7 clear it): halved back to the lowest centre that clears, within a tenth of e.
      double z_clear = c.z();
      auto clear = res;
      while (z_clear - z_below > 0.1 * e_) {
        c.z() = 0.5 * (z_below + z_clear);
        res = clearance_(c, clear.on_surface ? clear.foot : s.contact);
        if (res.reach() > target() + 1e-6) z_below = c.z(); else z_clear = c.z(), clear = res;
      }
      c.z() = z_clear;
      res = clear;
    }
    if (res.on_surface && (c - res.foot).norm() > 0) {
      // the ball now touches the surface at its foot point (or clears it by δ along the normal, or
      // reaches in by an inserted point's target)
      s.normal = (c - res.foot).normalized();
      s.contact = c - r_ * s.normal;
    } else {
      s.contact += Eigen::Vector3d(0, 0, c.z() - z0);
    }
    // (the lift's steps come short of a curved surface by a shrinking part: after 8 of them a
    // few reach in by 1e-6 to 5e-5 mm, on a 3 mm crest's clean cloud; what is left beyond 1 % of
    // e is reported)
    if (res.reach() > target() + 0.01 * e_) ++t.unresolved;
    if (c.z() - z0 > t.highest_lift)
      t.highest_lift = c.z() - z0, t.highest_lift_at = s.contact, t.highest_lift_from = planned;
    ++t.lifted;
    return true;
  }

  // A planned ball that reaches into what the trim left out (a wall beside a floor) is moved
  // sideways, away from the left-out point it reaches deepest, until it clears it, and set down
  // on the patch again: it then finishes the patch up to where the ball last reaches it, where a
  // lift would ride over the wall and leave the strip beside it too high (a floor beside a 10 mm
  // wall: the scallop there 0.091 mm, h 0.05). At most r sideways and 8 steps; false (the sample
  // unchanged) where that does not clear it: then it is lifted.
  bool push_off_left_out(Sample& s, BallClearance::Result res) const {
    const double keep_off = obstacle_keep_off(r_, clearance_.spacing());
    const Eigen::Vector3d planned = s.contact + r_ * s.normal;
    Eigen::Vector3d c = planned;
    for (int it = 0; it < 8; ++it) {
      if (!(res.reach() > position_tolerance(res))) break;
      if (!res.band_is_deepest() || !res.left_out_deepest) return false;
      const Eigen::Vector2d away = (c - res.left_out_at).head<2>();
      const double dz = c.z() - res.left_out_at.z();
      if (!(away.norm() > 1e-9) || !(std::abs(dz) < keep_off)) return false;
      c.head<2>() += (std::sqrt(keep_off * keep_off - dz * dz) - away.norm() + 1e-4) * away.normalized();
      if ((c - planned).head<2>().norm() > r_) return false;
      // set down on the patch again: touching its surface raised by the uncertainty there
      for (int k = 0; k < 8; ++k) {
        res = clearance_(c, c - r_ * Eigen::Vector3d::UnitZ());
        if (!res.on_surface || !(res.normal.z() > 0.2)) return false;
        const double dz_down = (res.clearance - res.uncertainty) / res.normal.z();
        c.z() -= dz_down;
        if (std::abs(dz_down) < 1e-6) break;
      }
      res = clearance_(c, c - r_ * Eigen::Vector3d::UnitZ());
    }
    if (res.reach() > position_tolerance(res) || !res.on_surface || !((c - res.foot).norm() > 0)) return false;
    s.normal = (c - res.foot).normalized();
    s.contact = c - r_ * s.normal;
    return true;
  }

  // How far the balls along the move from a to b reach into the band at most, checked at its
  // quarter points and points at most kProbeStep apart on long moves: the worst reach, where
  // (the fraction of the move) and what the clearance said there.
  double worst_along(const Sample& a, const Sample& b, double& at, BallClearance::Result& there) const {
    const Eigen::Vector3d ca = a.contact + r_ * a.normal, cb = b.contact + r_ * b.normal;
    const int probes = std::clamp(static_cast<int>(std::ceil((cb - ca).norm() / kProbeStep)), 4, 64);
    double worst = -INFINITY;
    at = 0.5;
    for (int j = 1; j < probes; ++j) {
      const double f = double(j) / probes;
      const auto res = clearance_((1 - f) * ca + f * cb, (1 - f) * a.contact + f * b.contact);
      if (res.reach() > worst) worst = res.reach(), at = f, there = res;
    }
    return worst;
  }

  // Appends to out the points to insert strictly between a and b (out.back() is a). A move still
  // too deep after max_splits halvings is listed in `stuck` by the index of its start in out.
  void refine(const Sample& a, const Sample& b, int depth, std::vector<Sample>& out, std::vector<std::size_t>& stuck,
              Tally& t) const {
    ++t.moves;
    double at;
    BallClearance::Result there;
    const double worst = worst_along(a, b, at, there);
    if (!(worst > move_tolerance(there))) return;
    if (depth >= max_splits_) {
      stuck.push_back(out.size() - 1);
      if (worst > t.deepest) t.deepest = worst, t.deepest_at = 0.5 * (a.contact + b.contact);
      return;
    }
    const Eigen::Vector3d ca = a.contact + r_ * a.normal, cb = b.contact + r_ * b.normal;
    Sample m;
    m.normal = ((1 - at) * a.normal + at * b.normal).normalized();
    m.contact = (1 - at) * ca + at * cb - r_ * m.normal;
    m.uv = (1 - at) * a.uv + at * b.uv;
    lift_if_needed(m, /*planned_position=*/false, t);
    ++t.inserted;
    refine(a, m, depth + 1, out, stuck, t);
    out.push_back(m);
    refine(m, b, depth + 1, out, stuck, t);
  }

  // A move still too deep after its halvings (the band's uncertainty changing faster along it
  // than the halvings can follow: on a 3 mm crest's clean cloud, moves 0.05 mm long whose ends
  // cleared it and whose middle reached 0.038 mm in) is raised whole: both ends go up until its
  // probes clear. Raising a ball never brings it nearer a height field's band (whatever lies
  // below a point of it does too), so the neighbouring moves stay clear.
  void raise_whole(Sample& a, Sample& b, Tally& t) const {
    double at, dz = 0;
    BallClearance::Result there;
    double worst = worst_along(a, b, at, there);
    for (int it = 0; it < 8 && worst > move_tolerance(there); ++it) {
      // to half the tolerance, or where it is a clearance half as much again clear
      const double tol = move_tolerance(there), target = tol > 0 ? 0.5 * tol : 1.5 * tol;
      const double step = (worst - target) / rise_rate(there);
      a.contact.z() += step, b.contact.z() += step, dz += step;
      worst = worst_along(a, b, at, there);
    }
    ++t.raised_moves;
    if (worst > move_tolerance(there)) ++t.unresolved;
    if (dz > t.highest_lift)
      t.highest_lift = dz, t.highest_lift_at = a.contact, t.highest_lift_from = a.contact + r_ * a.normal - Eigen::Vector3d(0, 0, dz);
  }

  // The positions are lifted, then the moves between them refined, each independently of the
  // others: in blocks of kBlock across threads (a rim pass of a million-point cloud, 4 793
  // positions beyond the cloud's edge, took 1.7 s alone on one thread while the other had
  // finished every other pass), the blocks' tallies added in order, so the result is the one
  // pass in order gives. A move raised whole moves its ends, which the next move shares: those
  // stay in order.
  ToolpathPass guard(const ToolpathPass& p, Tally& t) const {
    constexpr std::size_t kBlock = 64;
    const bool has_uv = p.uv.size() == p.contact.size();
    const std::size_t n = p.contact.size(), blocks = (n + kBlock - 1) / kBlock;
    std::vector<Sample> s(n);
    std::vector<Tally> lifts(blocks);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
      for (std::size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
        s[i] = {p.contact[i], p.normal[i], has_uv ? p.uv[i] : Eigen::Vector2d::Zero()};
        ++lifts[b].positions;
        lift_if_needed(s[i], /*planned_position=*/true, lifts[b]);
      }
    });
    for (const Tally& x : lifts) t.add(x);
    // Each block's moves: from the position before its first (held as its out[0]) to its last.
    struct Moves {
      std::vector<Sample> out;
      std::vector<std::size_t> stuck;  // indices into out, as refine gives them
      Tally t;
    };
    std::vector<Moves> moves(blocks);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
      Moves& m = moves[b];
      const std::size_t lo = b * kBlock, hi = std::min(n, lo + kBlock);
      if (lo > 0) m.out.push_back(s[lo - 1]);
      for (std::size_t i = lo; i < hi; ++i) {
        if (i > 0) refine(s[i - 1], s[i], 0, m.out, m.stuck, m.t);
        m.out.push_back(s[i]);
      }
    });
    std::vector<Sample> out;
    std::vector<std::size_t> stuck;
    out.reserve(s.size());
    for (std::size_t b = 0; b < blocks; ++b) {
      Moves& m = moves[b];
      const std::size_t offset = out.empty() ? 0 : out.size() - 1;  // where m.out[0] is in out
      for (std::size_t k : m.stuck) stuck.push_back(offset + k);
      out.insert(out.end(), m.out.begin() + (b > 0 ? 1 : 0), m.out.end());
      t.add(m.t);
    }
    for (std::size_t k : stuck) raise_whole(out[k], out[k + 1], t);
    ToolpathPass q;
    for (const auto& x : out) {
      q.contact.push_back(x.contact);
      q.normal.push_back(x.normal);
      if (has_uv) q.uv.push_back(x.uv);
    }
    return q;
  }

 private:
  const BallClearance& clearance_;
  double r_, e_, tol_, chord_tol_;
  int max_splits_;
};

nlohmann::json point_json(const Eigen::Vector3d& p) { return {{"x", p.x()}, {"y", p.y()}, {"z", p.z()}}; }

}  // namespace

GougeGuardResult guard_gouges(const Toolpath& path, const BallClearance& clearance,
                              const GougeGuardOptions& o) {
  path.check_passes();
  const double r = path.tool_radius, e = path.chord_error;
  const double tol = o.tolerance;  // <= 0: per position (PassGuard::position_tolerance)
  const double chord_tol = o.chord_tolerance;  // <= 0: per move (PassGuard::move_tolerance)
  if (o.max_splits < 0) throw std::invalid_argument("max_splits must be >= 0");

  GougeGuardResult res;
  res.path = path;
  const std::size_t n = path.passes.size();
  PassGuard guard(clearance, r, e, tol, chord_tol, o.max_splits);
  Tally total;
  std::mutex mu;
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& range) {
    Tally t;
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      res.path.passes[i] = guard.guard(path.passes[i], t);
      const std::size_t d = ++done;
      if (o.progress && d % 16 == 0) o.progress(double(d) / double(n));
    }
    std::lock_guard<std::mutex> lock(mu);
    total.add(t);
  });
  if (o.progress) o.progress(1.0);
  // A lift of several tool radii does not correct a plan, it hides one that has left the surface
  // (e.g. where the (u,v) map folds over): the path would cut air there, or worse.
  if (total.highest_lift > kMaxLiftRadii * r) {
    const Eigen::Vector3d& c = total.highest_lift_from;
    std::string why = "the plan does not follow the surface there, e.g. a fold-over of the (u,v) map";
    // How far the ball's disc in xy reaches off the patch (16 directions).
    double off_patch = 0;
    if (const Outline* outline = clearance.outline(); outline && !outline->empty())
      for (int k = 0; k < 16; ++k) {
        const double a = k * std::numbers::pi / 8;
        off_patch = std::max(off_patch, outline->beyond(c.head<2>() + r * Eigen::Vector2d(std::cos(a), std::sin(a))));
      }
    if (off_patch > 0)
      why = "the ball reaches " + short_number(off_patch) +
            " mm beyond the patch's outline, where the surface is only extrapolated from the cloud's points: "
            "a region left out beside the patch rises there (a steep wall cloud.trim_steep cut off beside a "
            "floor, say), or " + why;
    throw std::runtime_error("the planned ball at (" + short_number(c.x()) + ", " + short_number(c.y()) + ", " + short_number(c.z()) +
                             ") would have to be lifted by " + short_number(total.highest_lift) + " mm (> " +
                             short_number(kMaxLiftRadii) + " tool radii, " + short_number(kMaxLiftRadii * r) +
                             " mm) to clear the cloud's surface: " + why);
  }

  nlohmann::json rep;
  rep["tolerance"] = tol > 0 ? tol : 0.25 * e;
  rep["tolerance_adds_planned_reach"] = !(tol > 0);
  rep["chord_tolerance"] = chord_tol > 0 ? chord_tol : 0.9 * e;
  rep["chord_tolerance_less_uncertainty"] = !(chord_tol > 0);
  rep["positions_checked"] = total.positions;
  rep["moves_checked"] = total.moves;
  rep["lifted_positions"] = total.lifted;
  rep["inserted_positions"] = total.inserted;
  rep["raised_moves"] = total.raised_moves;
  rep["pushed_off_left_out"] = total.pushed;
  rep["unresolved"] = total.unresolved;
  rep["deepest_cut_in"] = total.deepest;
  if (total.deepest > 0) rep["deepest_cut_in_at"] = point_json(total.deepest_at);
  rep["highest_lift"] = total.highest_lift;
  if (total.highest_lift > 0) rep["highest_lift_at"] = point_json(total.highest_lift_at);
  nlohmann::json warnings = nlohmann::json::array();
  if (total.lifted > 0 || total.raised_moves > 0)
    warnings.push_back(std::to_string(total.lifted) + " tool positions (" + std::to_string(total.inserted) +
                       " of them added in the middle of moves) were lifted by up to " + short_number(total.highest_lift) +
                       " mm (most near x " + short_number(total.highest_lift_at.x()) + ", y " + short_number(total.highest_lift_at.y()) +
                       ") where the planned ball would have cut up to " + short_number(total.deepest) +
                       " mm into the cloud's surface (raised by its uncertainty)" +
                       (total.raised_moves > 0 ? ", and " + std::to_string(total.raised_moves) +
                                                     " moves still too deep after their halvings were raised whole"
                                               : std::string()) +
                       "; the path leaves that much stock there");
  if (total.unresolved > 0)
    warnings.push_back(std::to_string(total.unresolved) + " places still cut in after lifting, " +
                       std::to_string(o.max_splits) + " halvings of their moves and raising them whole (deepest near x " +
                       short_number(total.deepest_at.x()) + ", y " + short_number(total.deepest_at.y()) + ")");
  rep["warnings"] = warnings;
  res.report = std::move(rep);
  return res;
}

}  // namespace scallop
