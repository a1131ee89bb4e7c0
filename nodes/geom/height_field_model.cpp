#include "nodes/geom/height_field_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>

#include "nodes/cloud/denoise.h"
#include "nodes/geom/angular_gap.h"
#include "nodes/geom/grid_knn_2d.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/normal_equations.h"

namespace scallop {

constexpr double kPi = 3.14159265358979323846;

// How far the model's fit may be off the real surface beyond the points' own uncertainty: its
// shape bias, bounded by kMisfitFactor times its misfit, the largest residual of a neighbour
// beyond that neighbour's uncertainty (what the points' noise cannot explain: a crest, a crease;
// on a clean cloud, all of the error). Measured with bench/extra_surfaces.py model-error (this
// model, bench/height_field_error.cpp, at 20 000 to 26 000 places between the points of the
// catalog's 50k-point clouds as the shipped graph denoises them, rims included), the largest
// |error| / uncertainty, without the misfit and with 3 times it: clean freeform 2.67 and 0.59,
// canopy 1.04 and 0.46, crests of radius 3 and 1 mm 78 and 0.72, 413 and 0.48 (their points are
// exact, a quadratic over 20 of them is not); noisy (sigma 0.02) catalog surfaces at most 0.94
// either way, the 3 mm crest 0.96, the 1 mm crest 1.77 and 1.34 (where its crest runs out at
// the rim: a one-sided fit over points whose own uncertainty hides the bias). Re-measured on
// 2026-12-04 with 3 times it on 22 clouds (the 7 catalog surfaces and crests of 1 mm at slopes
// 0.7 and 0.3 turned 30 degrees, 3 mm and 10 mm; clean and noisy): at most 0.80, but for the
// clean 1 mm crest of slope 0.3, 1.12 (an error of 0.00014 mm where the uncertainty is 0.00012).
// Tried: carrying the points' uncertainties through the fit's weights (|sum_j l_j delta_j|,
// larger at a rim) brought the 1 mm crest to 0.99 but raised the bundled example's corners to
// 0.027 mm and failed its certificate (scallop 0.0555) where the error is 0.0005 mm; the bound
// for independent errors, sum_j |l_j| delta_j, was 1.38 times the mean inside a noisy plane.
// Tried too (2026-12-04): a smoother misfit, each residual counted by a weight falling with the
// neighbour's distance ((1 - d^2/D^2)^2, 1 - d^2/D^2, the fit's own Gaussian weight, or only the
// inner half of the disc): the largest |error| / uncertainty rose on all four clean crests (1, 3
// and 10 mm; 0.48-1.12 to 1.47-4.83), the noisy 1 mm crest (0.77 to 0.96-1.06), the clean
// freeform (0.55 to 0.70-0.83) and canopy (0.44 to 0.54-0.71): the far neighbours' residuals are
// what reveals the quadric's bias at the centre. And a two-scale estimate of the bias, the
// difference of this fit and one over the 40 nearest: in place of the misfit, up to 148 on the
// clean crests (where both fits are biased alike they agree); added to the misfit alone (no
// factor), 1.00-1.31 there. And, where the misfit is large, the fit over the 10, 12 or 15
// nearest when its misfit is smaller: 2.4-19.5 on the clean crests, the noisy 1 mm crest 1.36,
// and the largest error no smaller (a fit with fewer spare points shows less of its bias).
// (50 000-point clouds, seed 1, as the shipped graph denoises them; bench/extra_surfaces.py
// model-error.)
constexpr double kMisfitFactor = 3.0;

// Where the quadratic's bound on its bias (kMisfitFactor times its misfit) is over this (mm), a
// quartic over twice its neighbours is fitted too (of z over (x, y), or of w(a, b) in the local
// fit's tangent frame where the surface is steep), and kept when it misfits the quadratic's
// points less and agrees with it (Impl::keep_better); its bound is kMisfitFactor times that
// misfit plus its difference from the quadratic. A crest of radius 3 mm bent the quadratic's far
// points away by 0.01 mm while its value at the centre was 0.001 mm off: held off the top by
// that bound, the ball left 0.068 mm of scallop where h was 0.05 (the catalog's 3 mm crest, stop
// 77). (bench/extra_surfaces.py
// model-error, the 24 clouds above, clean and noisy; stop 78.) With the quartic, the largest
// |error| / uncertainty is unchanged on 23 clouds and 0.48 -> 0.57 on the clean 1 mm crest;
// the 99th percentile of the uncertainty falls 0.0265 -> 0.0022 mm on the clean 3 mm crest,
// 0.147 -> 0.031 on the 1 mm one, 0.0028 -> 0.00095 on the freeform patch; the largest error
// falls too (0.0086 -> 0.0029 mm on the 3 mm crest). The quartic's misfit over all its 40
// points instead of the quadratic's 20 gave a 99th percentile of 0.0037 there, 0.054 on the
// 1 mm crest. On noisy clouds the quadratic's misfit beyond the points' uncertainty rarely
// reaches this, and nothing changed. Below it the quartic is not tried: it costs 15 x 15 normal
// equations over 40 points. In the tangent frame (steep places; the same day): on the clean
// canopy's steep flank, where its zig-zag certificate failed on gouge bounds of 0.011 mm, the
// uncertainty 0.0034 -> 0.0004 mm at those places; its 99th percentile 0.00099 -> 0.00086, the
// largest |error| / uncertainty unchanged (0.44), the other 23 clouds unchanged.
// Tried (stop 79): the quartic's residuals in its bound weighted to fall to 0 at the 20th point,
// so that a point leaving takes its residual out gradually (the bound is a saw-tooth across a
// crest, 0.0013 -> 0.0025 -> 0.0013 mm within 0.1 mm on the clean 3 mm crest, and the guard,
// which samples it at its probes, and the certificate, between them, see different teeth).
// By 1 - (d / d20)^4: the 99th percentile of the uncertainty 0.0022 -> 0.0019 mm on that crest,
// but the largest |error| / uncertainty of the clean 1 mm crest of slope 0.3 rose 1.12 -> 1.20,
// at an error of 0.019 mm, and the 3 mm crest's certificates traded places (zig-zag passing,
// contour failing at the rim, gouge bound 0.0103). By a ramp over the outer 20 % of the disc's
// area: ratios unchanged, the zig-zag failing again (0.0105): the bound still jumps 5-fold within
// 0.01 mm where the quadratic beneath it changes neighbours (its difference from the quartic
// counts too). Neither kept. Tried on the guard's side the same day: the band sampled also half
// a spacing around each point where the uncertainty may change (surface_band), and the guard's
// foot held to the largest band uncertainty within a spacing of it: the catalog's 3 mm crest's
// certificates passed (gouge bounds 0.0096 / 0.0097, verify.py 0.0495 / 0.0498 whole patch,
// gouge 0.0086 / 0.0084), but on the tests' sparser 3 mm crest of slope 0.3 (5000 points) the
// guard lifted balls where the planner had not planned for it: the exact whole-patch scallop
// 0.049 -> 0.071 (0.056 with half a spacing). With the planner's strip margins held to the
// largest uncertainty within a spacing as well: 0.069, the interior 0.045. The excess is at the
// rim: the band's samples half a spacing out from the outermost points take the uncertainty
// grown beyond the edge, and the guard lifts the rim's balls. The catalog crest's contour
// program needed exactly that (its gouge bound was over e at the rim).
constexpr double kQuarticFrom = 1e-3;

struct HeightFieldModel::Impl {
  // The cloud: the caller's points, or the model's own when it was given them to keep. (It once
  // kept three copies, xy, z and 3-D: at a million points cloud.surface_band peaked at 778 MiB
  // with them, 515 without, and the surface band, planner, guard, link and certificate each
  // build a model.)
  std::vector<Eigen::Vector3d> owned;
  const std::vector<Eigen::Vector3d>& p;
  Impl(std::vector<Eigen::Vector3d>&& own, const std::vector<Eigen::Vector3d>* given)
      : owned(std::move(own)), p(given ? *given : owned) {}
  Eigen::Vector2d xy(std::uint32_t i) const { return p[i].head<2>(); }
  std::unique_ptr<GridKnn2d> grid;  // the k nearest in xy
  std::size_t nearest_xy(double x, double y, int k, std::uint32_t* idx, double* d2) const {
    return std::size_t(grid->query(Eigen::Vector2d(x, y), k, idx, d2));
  }
  std::unique_ptr<PointsAdaptor<Eigen::Vector3d>> adaptor3;
  // The 3-D tree of the steep fits (and of tree3d()'s other users), built on first use: a patch
  // gentle everywhere may never need it (half a second per million points, single-threaded).
  mutable std::once_flag tree3_built;
  mutable std::unique_ptr<KdTree<Eigen::Vector3d, 3>> tree3;
  const KdTree<Eigen::Vector3d, 3>& steep_tree() const {
    std::call_once(tree3_built, [this] {
      tree3 = std::make_unique<KdTree<Eigen::Vector3d, 3>>(3, *adaptor3, nanoflann::KDTreeSingleIndexAdaptorParams(16));
      tree3->buildIndex();
    });
    return *tree3;
  }
  const std::vector<double>* uncertainty = nullptr;  // per point (mm), or null

  double point_uncertainty(std::uint32_t i) const { return uncertainty ? (*uncertainty)[i] : 0.0; }
  // How much of a residual at point i its own error explains: its uncertainty less the floor
  // every cloud has (kUncertaintyFloor, a resolution, not a noise the fit averages out).
  // Counted in full before stop 88: on clean clouds (every point known to the floor, 1e-4 mm) a
  // quadratic whose residuals all lay within it was taken as unbiased, yet between the points it
  // was off by up to 1.24 times the floor (five clean crests of the family, errors of 1.0 to
  // 1.3e-4 mm; bench/extra_surfaces.py model-error). Counting them, the largest |error| /
  // uncertainty over the 19 clean clouds (the catalog's 7 and the 12 crests) is 0.83 at most;
  // the median uncertainty rises from the floor to 0.0001-0.0004 mm, its 99th percentile by at
  // most 0.0003 mm.
  double explained(std::uint32_t i) const { return std::max(0.0, point_uncertainty(i) - kUncertaintyFloor); }
  // The mean uncertainty of the points idx[0..got) (0 without uncertainties).
  double mean_uncertainty(const std::uint32_t* idx, std::size_t got) const;
  // The centroid in xy of the points idx[0..got), got > 0.
  Eigen::Vector2d centroid(const std::uint32_t* idx, std::size_t got) const;
  // The directions from (x, y) to the points idx[0..got), got <= 64.
  std::array<Eigen::Vector2d, 64> directions(double x, double y, const std::uint32_t* idx, std::size_t got) const;
  // How surely (x, y) lies beyond the cloud's edge: 0 inside, 1 where the points around it all
  // lie to one side; idx[0..got) its nearest points (a first look).
  double beyond_edge(double x, double y, const std::uint32_t* idx, std::size_t got) const;
  // The factor eval's uncertainty grows by at (x, y) beyond the edge (1 elsewhere; see eval);
  // idx, d2 its nearest points, ascending.
  double edge_growth(double x, double y, const std::uint32_t* idx, const double* d2, std::size_t got,
                     double spacing) const {
    const double gap = edge_gap(d2, spacing);
    return gap > 0 ? 1 + beyond_edge(x, y, idx, got) * gap / (2 * spacing) : 1.0;
  }
  // How far the nearest point (squared distance d2[0]) lies beyond the half spacing a
  // well-sampled edge has; and the largest factor edge_growth can give there (beyond_edge <= 1).
  static double edge_gap(const double* d2, double spacing) { return std::sqrt(d2[0]) - 0.5 * spacing; }
  static double edge_growth_max(const double* d2, double spacing) {
    const double gap = edge_gap(d2, spacing);
    return gap > 0 ? 1 + gap / (2 * spacing) : 1.0;
  }
  // The local fit where the surface is steep, else the fit of z over (x, y); either replaced by
  // a quartic where it misfits (see kQuarticFrom).
  bool fit(double x, double y, const std::uint32_t* idx, const double* d2, std::size_t got, int k, double& z,
           Eigen::Vector3d& normal, double& misfit) const {
    XyWeights xw;
    xy_weights(x, y, idx, d2, got, xw);
    if (!surely_gentle(idx, got, xw) && local_fit(x, y, idx, d2, got, k, z, normal, misfit)) return true;
    if (!xy_fit(idx, got, xw, z, normal, misfit)) return false;
    if (kMisfitFactor * misfit > kQuarticFrom) quartic_fit(x, y, got, z, normal, misfit);
    return true;
  }
  // The xy fit's basis and Gaussian weights at (x, y) over its nearest points: the test for a
  // gentle slope takes the same weights (each costs an exp; a fifth of an evaluation's time
  // went to the two sets, which differed only in rounding).
  struct XyWeights {
    double h;                                          // the farthest neighbour's distance (mm)
    std::array<Eigen::Matrix<double, 6, 1>, 64> basis;  // 1, u, v, u², uv, v² in units of h
    std::array<double, 64> w;
  };
  void xy_weights(double x, double y, const std::uint32_t* idx, const double* d2, std::size_t got,
                  XyWeights& out) const;
  // Whether a bound already puts the least-variance direction of the weighted points within 37
  // degrees of +z, where the xy fit is as good as the local one and cheaper.
  bool surely_gentle(const std::uint32_t* idx, std::size_t got, const XyWeights& xw) const;
  // The fits: z and normal at (x, y), and their misfit (mm; see kMisfitFactor); idx, d2 the
  // nearest points in xy and their squared distances, ascending, as the search gave them.
  bool local_fit(double x, double y, const std::uint32_t* idx, const double* d2, std::size_t got, int k,
                 double& z, Eigen::Vector3d& normal, double& misfit) const;
  bool xy_fit(const std::uint32_t* idx, std::size_t got, const XyWeights& xw, double& z, Eigen::Vector3d& normal,
              double& misfit) const;
  // Replaces the quadratic xy fit (z, normal, misfit, over its `got` nearest points) by a quartic
  // over twice as many when the quartic misfits those points less and agrees with the quadratic
  // (see kQuarticFrom); the misfit then counts the two fits' difference too.
  void quartic_fit(double x, double y, std::size_t got, double& z, Eigen::Vector3d& normal, double& misfit) const;
  // The same for the local fit: a quartic w(a, b) in the frame F about o (the quadratic's point
  // and frame) over twice the quadratic's `got` nearest points in 3-D, its point above (x, y).
  void local_quartic_fit(double x, double y, const Eigen::Vector3d& o, const Eigen::Matrix3d& F, std::size_t got,
                         double& z, Eigen::Vector3d& normal, double& misfit) const;
  // Puts the quartic (its z, normal and misfit over the quadratic's points) in place of the
  // quadratic's (z, normal, misfit) where it fits better and agrees with it; see quartic_fit.
  static void keep_better(double quartic_z, const Eigen::Vector3d& quartic_normal, double quartic_misfit, double& z,
                          Eigen::Vector3d& normal, double& misfit);
};

namespace {

// Weighted centroid and unit normal (least-variance direction, turned up) of points `idx`,
// Gaussian weights of width h about o. False when the normal is within ~1 degree of horizontal
// (a wall: no height there) or the points are degenerate.
bool local_plane(const std::vector<Eigen::Vector3d>& P, const std::uint32_t* idx, std::size_t got,
                 const Eigen::Vector3d& o, double h, Eigen::Vector3d& centroid, Eigen::Matrix3d& frame) {
  double wsum = 0;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  std::array<double, 64> w;  // got <= 64
  for (std::size_t j = 0; j < got; ++j) {
    w[j] = std::exp(-2.0 * (P[idx[j]] - o).squaredNorm() / (h * h));
    m += w[j] * P[idx[j]];
    wsum += w[j];
  }
  if (!(wsum > 0)) return false;
  m /= wsum;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < got; ++j) {
    const Eigen::Vector3d d = P[idx[j]] - m;
    C += w[j] * d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  if (es.info() != Eigen::Success || !(es.eigenvalues()[1] > 1e-6 * es.eigenvalues()[2])) return false;
  Eigen::Vector3d n = es.eigenvectors().col(0);
  if (n.z() < 0) n = -n;
  if (n.z() < 0.02) return false;
  frame.col(2) = n;
  frame.col(0) = es.eigenvectors().col(2);
  frame.col(1) = n.cross(frame.col(0));
  centroid = m;
  return true;
}

// The point P = o + h (a t1 + b t2 + w(a, b) n) of a graph w over the frame F about o (t1, t2, n
// its columns) that lies above (x, y), found by Newton's method on (a, b) from 0, and its upward
// unit normal. `w_at(a, b, wa, wb)` returns w and sets its partial derivatives. False where the
// Jacobian is singular, Newton does not converge in 20 steps or (a, b) leaves |a|, |b| <= reach.
template <class Graph>
bool point_above(double x, double y, const Eigen::Vector3d& o, const Eigen::Matrix3d& F, double h, double reach,
                 const Graph& w_at, Eigen::Vector3d& P, Eigen::Vector3d& normal) {
  double a = 0, b = 0;
  for (int it = 0; it < 20; ++it) {
    double wa, wb;
    const double w = w_at(a, b, wa, wb);
    P = o + h * (a * F.col(0) + b * F.col(1) + w * F.col(2));
    const Eigen::Vector3d ta = F.col(0) + wa * F.col(2), tb = F.col(1) + wb * F.col(2);
    const Eigen::Vector2d res(P.x() - x, P.y() - y);
    if (res.norm() < 1e-12 * (1 + h)) {
      normal = ta.cross(tb).normalized();
      if (normal.z() < 0) normal = -normal;
      return true;
    }
    Eigen::Matrix2d J;
    J << ta.x(), tb.x(), ta.y(), tb.y();
    J *= h;
    if (!(std::abs(J.determinant()) > 1e-12 * h * h)) return false;
    const Eigen::Vector2d step = J.inverse() * res;
    a -= step.x();
    b -= step.y();
    if (std::abs(a) > reach || std::abs(b) > reach) return false;  // left the neighbourhood
  }
  return false;
}

}  // namespace

// Moving least squares in a local frame (tangent plane of the neighbours, normal w): w(a, b) a
// quadratic, fitted to the k points nearest in 3-D to the current estimate, then the point of it
// above (x, y) found by Newton's method. Unlike a fit of z over (x, y), it stays accurate where
// the surface is steep and the neighbours crowd together in xy (rings of a sphere near its rim
// project onto nearly the same xy lines, and a quadratic in (x, y) through them is ill-posed).
bool HeightFieldModel::Impl::local_fit(double x, double y, const std::uint32_t* idx_xy, const double* d2_xy,
                                       std::size_t got_xy, int k, double& z_out, Eigen::Vector3d& n_out,
                                       double& misfit) const {
  Eigen::Vector3d m;
  Eigen::Matrix3d F;
  const double hxy = std::sqrt(d2_xy[got_xy - 1]);  // the farthest neighbour in xy
  // First estimate: the plane through the points nearest to the vertical line at (x, y).
  Eigen::Vector3d o(x, y, 0);
  {
    // weights only on the xy distance here: the z spread is what is unknown
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double wsum = 0;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    std::array<double, 64> w;  // got_xy <= 64
    for (std::size_t j = 0; j < got_xy; ++j) {
      w[j] = std::exp(-2.0 * d2_xy[j] / (hxy * hxy + 1e-300));
      c += w[j] * p[idx_xy[j]];
      wsum += w[j];
    }
    c /= wsum;
    for (std::size_t j = 0; j < got_xy; ++j) C += w[j] * (p[idx_xy[j]] - c) * (p[idx_xy[j]] - c).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    Eigen::Vector3d n = es.eigenvectors().col(0);
    if (n.z() < 0) n = -n;
    if (es.info() != Eigen::Success || n.z() < 0.02) return false;
    // Up to ~37 degrees the fit of z over (x, y) below is as good and cheaper.
    if (n.z() > 0.8) return false;
    o.z() = c.z() - (n.x() * (x - c.x()) + n.y() * (y - c.y())) / n.z();
  }
  std::uint32_t idx[64];
  double d2[64];
  const int kk = std::min(k, 64);
  std::size_t got = 0;
  for (int round = 0; round < 3; ++round) {
    got = steep_tree().knnSearch(o.data(), kk, idx, d2);
    if (got < 6) return false;
    const double h = std::sqrt(d2[got - 1]) + 1e-12;
    if (!local_plane(p, idx, got, o, 2 * h, m, F)) return false;
    // w = c0 + c1 a + c2 b + c3 a^2 + c4 ab + c5 b^2 in units of h about o, frame F
    Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    for (std::size_t j = 0; j < got; ++j) {
      const Eigen::Vector3d l = F.transpose() * (p[idx[j]] - o) / h;
      const double w = std::exp(-2.0 * (l.x() * l.x() + l.y() * l.y()));
      Eigen::Matrix<double, 6, 1> b;
      b << 1, l.x(), l.y(), l.x() * l.x(), l.x() * l.y(), l.y() * l.y();
      add_weighted_outer_lower(M, b, w);
      rhs += w * l.z() * b;
    }
    Eigen::Matrix<double, 6, 1> c;
    if (!solve_positive_definite(M, rhs, c, 1e-8)) return false;
    const auto quadratic = [&c](double a, double b, double& wa, double& wb) {
      wa = c[1] + 2 * c[3] * a + c[4] * b;
      wb = c[2] + c[4] * a + 2 * c[5] * b;
      return c[0] + c[1] * a + c[2] * b + c[3] * a * a + c[4] * a * b + c[5] * b * b;
    };
    Eigen::Vector3d P, n;
    if (!point_above(x, y, o, F, h, 3.0, quadratic, P, n)) return false;
    misfit = 0;
    for (std::size_t j = 0; j < got; ++j) {
      const Eigen::Vector3d l = F.transpose() * (p[idx[j]] - o) / h;
      const double fitted = c[0] + c[1] * l.x() + c[2] * l.y() + c[3] * l.x() * l.x() +
                            c[4] * l.x() * l.y() + c[5] * l.y() * l.y();
      misfit = std::max(misfit, h * std::abs(l.z() - fitted) - explained(idx[j]));
    }
    const double moved = (P - o).norm();
    o = P;
    z_out = P.z();
    n_out = n;
    if (moved < 0.05 * h) break;  // the neighbourhood is centred on the point found
  }
  if (kMisfitFactor * misfit > kQuarticFrom) local_quartic_fit(x, y, o, F, got, z_out, n_out, misfit);
  return true;
}

HeightFieldModel::HeightFieldModel(const std::vector<Eigen::Vector3d>& P, int k,
                                   const std::vector<double>* uncertainty)
    : HeightFieldModel({}, &P, k, uncertainty) {}

HeightFieldModel::HeightFieldModel(std::vector<Eigen::Vector3d>&& P, int k, const std::vector<double>* uncertainty)
    : HeightFieldModel(std::move(P), nullptr, k, uncertainty) {}

HeightFieldModel::HeightFieldModel(std::vector<Eigen::Vector3d>&& own, const std::vector<Eigen::Vector3d>* given,
                                   int k, const std::vector<double>* uncertainty)
    : k_(k) {
  const std::vector<Eigen::Vector3d>& P = given ? *given : own;
  if (P.size() < 10)
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; the surface model needs at least 10");
  if (uncertainty && uncertainty->size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) + " points but " +
                                std::to_string(uncertainty->size()) + " uncertainties");
  if (uncertainty)
    for (double u : *uncertainty) uncertainty_max_ = std::max(uncertainty_max_, u);
  k_ = std::min<int>(k, static_cast<int>(P.size()));
  lo_ = Eigen::Vector2d(INFINITY, INFINITY);
  hi_ = -lo_;
  zmax_ = -INFINITY;
  for (const auto& p : P) {
    if (!p.allFinite()) throw std::invalid_argument("the cloud has a non-finite point");
    lo_ = lo_.cwiseMin(p.head<2>());
    hi_ = hi_.cwiseMax(p.head<2>());
    zmax_ = std::max(zmax_, p.z());
  }
  auto impl = std::make_unique<Impl>(std::move(own), given);  // (`own` is moved from: P is impl->p now)
  impl->uncertainty = uncertainty;
  impl->grid = std::make_unique<GridKnn2d>(impl->p);
  impl->adaptor3 = std::make_unique<PointsAdaptor<Eigen::Vector3d>>(PointsAdaptor<Eigen::Vector3d>{impl->p});
  // Mean spacing from the 8th-neighbour distance: in a uniform sample of density ρ, π ρ r₈² ≈ 8.
  const std::size_t n = impl->p.size(), stride = std::max<std::size_t>(1, n / 2000);
  std::vector<double> r8;
  const int kk = std::min<int>(9, static_cast<int>(n));
  std::vector<std::uint32_t> idx(kk);
  std::vector<double> d2(kk);
  for (std::size_t i = 0; i < n; i += stride) {
    std::size_t got = impl->nearest_xy(impl->p[i].x(), impl->p[i].y(), kk, idx.data(), d2.data());
    r8.push_back(std::sqrt(d2[got - 1]));
  }
  std::nth_element(r8.begin(), r8.begin() + r8.size() / 2, r8.end());
  spacing_ = r8[r8.size() / 2] * std::sqrt(kPi / (kk - 1));
  impl_ = impl.release();
}

HeightFieldModel::~HeightFieldModel() { delete impl_; }

const std::vector<Eigen::Vector3d>& HeightFieldModel::points() const { return impl_->p; }
const KdTree<Eigen::Vector3d, 3>& HeightFieldModel::tree3d() const { return impl_->steep_tree(); }

double HeightFieldModel::Impl::mean_uncertainty(const std::uint32_t* idx, std::size_t got) const {
  if (!uncertainty || got == 0) return 0;
  double sum = 0;
  for (std::size_t j = 0; j < got; ++j) sum += (*uncertainty)[idx[j]];
  return sum / got;
}

Eigen::Vector2d HeightFieldModel::Impl::centroid(const std::uint32_t* idx, std::size_t got) const {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (std::size_t j = 0; j < got; ++j) c += xy(idx[j]);
  return c / double(got);
}

std::array<Eigen::Vector2d, 64> HeightFieldModel::Impl::directions(double x, double y, const std::uint32_t* idx,
                                                                   std::size_t got) const {
  std::array<Eigen::Vector2d, 64> d;
  for (std::size_t j = 0; j < got; ++j) d[j] = xy(idx[j]) - Eigen::Vector2d(x, y);
  return d;
}

double HeightFieldModel::Impl::beyond_edge(double x, double y, const std::uint32_t* idx, std::size_t got) const {
  // The widest angle between neighbouring directions to the 64 nearest points, as boundary
  // detection uses it: at least pi beyond a straight edge; at most 0.41 pi measured inside the
  // freeform patch's denoised 50k-point cloud, in 1808 holes whose nearest point was 0.6 to
  // 0.9 mm away (with the 20 nearest points, up to pi: too few to tell a hole from an edge).
  constexpr double kFrom = 0.6 * kPi, kTo = 0.9 * kPi;
  // fewer points cannot close a wide gap
  if (!angular_gap_exceeds(directions(x, y, idx, got).data(), got, kFrom)) return 0;
  std::uint32_t wide[64];
  double d2[64];
  const std::size_t got_wide = nearest_xy(x, y, 64, wide, d2);
  // (Bins of the directions settle most places without sorting them: no 3 empty in a row, no gap
  // reaches kFrom; 9 in a row, the gap is wider than kTo. angular_gap.h.)
  const auto around = directions(x, y, wide, got_wide);
  const int empty_run = longest_empty_bin_run(around.data(), got_wide);
  if (empty_run < 3) return 0;
  if (empty_run >= 9) return 1;
  const double widest = largest_angular_gap(around.data(), got_wide);
  return std::clamp((widest - kFrom) / (kTo - kFrom), 0.0, 1.0);
}

double HeightFieldModel::reach_beyond(double x, double y) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t got = impl_->nearest_xy(x, y, 64, idx, d2);
  const Eigen::Vector2d centroid = impl_->centroid(idx, got);
  const Eigen::Vector2d out = Eigen::Vector2d(x, y) - centroid;
  if (!(out.norm() > 0)) return -INFINITY;
  const Eigen::Vector2d dir = out.normalized();
  double farthest = -INFINITY;
  for (std::size_t j = 0; j < got; ++j) farthest = std::max(farthest, (impl_->xy(idx[j]) - centroid).dot(dir));
  return out.norm() - farthest;
}

bool HeightFieldModel::uncertainty_may_grow(double x, double y, double misfit_floor) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t got = impl_->nearest_xy(x, y, std::min(k_, 64), idx, d2);
  if (got == 0) return true;
  if (impl_->edge_growth(x, y, idx, d2, got, spacing_) > 1) return true;
  double z, misfit = 0;
  Eigen::Vector3d n;
  if (!impl_->fit(x, y, idx, d2, got, k_, z, n, misfit)) return true;
  return kMisfitFactor * misfit > misfit_floor;
}

double HeightFieldModel::uncertainty(double x, double y) const {
  double z, u = 0;
  Eigen::Vector3d n;
  eval(x, y, z, n, /*force=*/true, &u);
  return u;
}

// A step halved back below this (mm) ends the foot search: the field, a fit over neighbours that
// change from place to place, is not smooth at the last digits, and the halvings went on to 1e-7
// at three searches in four on the bundled example (353 000 of the guard's 489 000 fits there).
// 1e-4 mm beside the nearest place the distance to c is longer by a second-order amount, below
// 1e-8 mm for any curvature the ball can follow; the bundled example's G-code is the same.
constexpr double kFootTolerance = 1e-4;

bool HeightFieldModel::foot_point(const Eigen::Vector3d& c, const Eigen::Vector2d& start, double max_step,
                                  Eigen::Vector2d& at) const {
  // Measured on a crest of radius 3 mm under a ball of radius 4 (the projection overshoots by
  // 4 / 3 there): undamped, the search ended on the flank 1.1 mm from the nearest place, and the
  // ball seemed to clear the field by 0.026 mm where it cut 0.009 mm into it.
  Eigen::Vector2d s = start, step = Eigen::Vector2d::Zero();
  double nearest_d2 = INFINITY, z;
  Eigen::Vector3d n;
  bool found = false;
  for (int it = 0; it < 24; ++it) {
    if (!eval(s.x(), s.y(), z, n, /*force=*/true)) break;
    const Eigen::Vector3d p(s.x(), s.y(), z);
    const double d2 = (c - p).squaredNorm();
    if (found && d2 > nearest_d2) {
      step *= 0.5;
      if (step.norm() < kFootTolerance) break;
      s = at + step;
      continue;
    }
    found = true, at = s, nearest_d2 = d2;
    Eigen::Vector2d next = (c - (c - p).dot(n) * n).head<2>();
    if ((next - s).norm() > max_step) next = s + max_step * (next - s).normalized();
    step = next - s;
    s = next;
    if (step.norm() < 1e-7) {
      at = s;
      break;
    }
  }
  return found;
}

bool HeightFieldModel::eval_before_growth(double x, double y, double& z, Eigen::Vector3d& normal,
                                          double& before_growth, double& growth_max) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t got = impl_->nearest_xy(x, y, std::min(k_, 64), idx, d2);
  if (got == 0) return false;
  const double points_uncertainty = impl_->mean_uncertainty(idx, got);
  growth_max = Impl::edge_growth_max(d2, spacing_);
  double misfit = 0;
  if (!impl_->fit(x, y, idx, d2, got, k_, z, normal, misfit)) return false;
  before_growth = points_uncertainty + kMisfitFactor * misfit;
  return true;
}

double HeightFieldModel::edge_growth(double x, double y) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t got = impl_->nearest_xy(x, y, std::min(k_, 64), idx, d2);
  return got == 0 ? 1.0 : impl_->edge_growth(x, y, idx, d2, got, spacing_);
}

bool HeightFieldModel::inside(double x, double y) const {
  double z;
  Eigen::Vector3d n;
  return eval(x, y, z, n);
}

bool HeightFieldModel::eval(double x, double y, double& z, Eigen::Vector3d& normal, bool force,
                       double* uncertainty) const {
  const int k = k_;
  std::uint32_t idx[64];
  double d2[64];
  std::size_t got = impl_->nearest_xy(x, y, std::min(k, 64), idx, d2);
  if (got == 0) return false;
  // Beyond the edge, a gap in the data (the nearest point farther than the half spacing a
  // well-sampled edge has) is an extrapolation, known the less the farther it reaches:
  // measured on the noisy freeform patch (sigma 0.02, spacing 0.5), the fit 0.89 mm from its
  // nearest rim points was 0.0195 mm low where they were known to 0.0115, a factor 1.7;
  // 1 + gap / (2 spacing) gives 1.64 there (the gouge budget covers the rest) and changes
  // slowly enough for a check at the ball's foot point to hold a few tenths of a mm around
  // it. Holes inside the patch are interpolated across and keep the points' uncertainty.
  double points_uncertainty = 0, growth = 1;
  if (uncertainty) {
    points_uncertainty = impl_->mean_uncertainty(idx, got);
    growth = impl_->edge_growth(x, y, idx, d2, got, spacing_);
    *uncertainty = points_uncertainty * growth;
  }
  // Beyond the edge of the cloud the neighbours are all on one side: their centroid moves off
  // (x, y) by about 0.42 of their radius already at the edge (half a disc).
  const bool outside =
      !force && (d2[0] > 2.25 * spacing_ * spacing_ ||
                 (impl_->centroid(idx, got) - Eigen::Vector2d(x, y)).squaredNorm() > 0.25 * d2[got - 1]);
  if (outside && !uncertainty) return false;
  // (fitted outside too when the uncertainty is asked: a check beside the patch, at a hole's
  // edge, must see the uncertainty the certificate sees there)
  double zf;
  Eigen::Vector3d nf;
  double misfit = 0;
  const bool fitted = impl_->fit(x, y, idx, d2, got, k, zf, nf, misfit);
  if (fitted && uncertainty) *uncertainty = (points_uncertainty + kMisfitFactor * misfit) * growth;
  if (!fitted || outside) return false;
  z = zf;
  normal = nf;
  return true;
}

namespace {

// The quartic's 15 monomials u^i v^j, i + j <= 4, and its weighted least-squares fit.
using QuarticBasis = Eigen::Matrix<double, 15, 1>;
QuarticBasis quartic_basis(double u, double v) {
  const double uu = u * u, uv = u * v, vv = v * v;
  QuarticBasis b;
  b << 1, u, v, uu, uv, vv, uu * u, uu * v, u * vv, vv * v, uu * uu, uu * uv, uu * vv, uv * vv, vv * vv;
  return b;
}
// The quartic's value and first derivatives at (u, v).
double quartic_at(const QuarticBasis& c, double u, double v, double& du, double& dv) {
  const double uu = u * u, uv = u * v, vv = v * v;
  du = c[1] + 2 * c[3] * u + c[4] * v + 3 * c[6] * uu + 2 * c[7] * uv + c[8] * vv + 4 * c[10] * uu * u +
       3 * c[11] * uu * v + 2 * c[12] * u * vv + c[13] * vv * v;
  dv = c[2] + c[4] * u + 2 * c[5] * v + c[7] * uu + 2 * c[8] * uv + 3 * c[9] * vv + c[11] * uu * u +
       2 * c[12] * uu * v + 3 * c[13] * u * vv + 4 * c[14] * vv * v;
  return quartic_basis(u, v).dot(c);
}
// Fits w over the points' (u, v) (in units of the fit's radius, Gaussian weights exp(-2 rho^2));
// false when the points do not determine a quartic.
bool fit_quartic(const std::array<Eigen::Vector3d, 64>& uvw, std::size_t got, QuarticBasis& c) {
  Eigen::Matrix<double, 15, 15> M = Eigen::Matrix<double, 15, 15>::Zero();
  QuarticBasis rhs = QuarticBasis::Zero();
  for (std::size_t j = 0; j < got; ++j) {
    const QuarticBasis b = quartic_basis(uvw[j].x(), uvw[j].y());
    const double w = std::exp(-2.0 * (uvw[j].x() * uvw[j].x() + uvw[j].y() * uvw[j].y()));
    add_weighted_outer_lower(M, b, w);
    rhs += w * uvw[j].z() * b;
  }
  return solve_positive_definite(M, rhs, c, 1e-8);
}

}  // namespace

void HeightFieldModel::Impl::keep_better(double quartic_z, const Eigen::Vector3d& quartic_normal,
                                         double quartic_misfit, double& z, Eigen::Vector3d& normal,
                                         double& misfit) {
  // Kept only where it fits better and agrees with the quadratic: its value within the
  // quadratic's bound and its normal within 10 degrees. Beyond the cloud's edge, where eval fits
  // to give the uncertainty, a quartic's slope extrapolates wildly (on a clean crest of radius
  // 0.5 mm running out at the rim, a ball beside it was then lifted by 34 mm and the guard
  // refused the plan).
  if (!(quartic_misfit < misfit) || !(std::abs(quartic_z - z) < kMisfitFactor * misfit) ||
      quartic_normal.dot(normal) < std::cos(10 * kPi / 180))
    return;
  misfit = quartic_misfit + std::abs(quartic_z - z) / kMisfitFactor;
  z = quartic_z;
  normal = quartic_normal;
}

void HeightFieldModel::Impl::quartic_fit(double x, double y, std::size_t got_quadratic, double& z,
                                         Eigen::Vector3d& normal, double& misfit) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t want = std::min<std::size_t>(2 * got_quadratic, 64);
  const std::size_t got = nearest_xy(x, y, int(want), idx, d2);
  if (got < want) return;
  const double h = std::sqrt(d2[got - 1]) + 1e-12;
  std::array<Eigen::Vector3d, 64> uvw;
  for (std::size_t j = 0; j < got; ++j) uvw[j] = {(p[idx[j]].x() - x) / h, (p[idx[j]].y() - y) / h, p[idx[j]].z()};
  QuarticBasis c;
  if (!fit_quartic(uvw, got, c)) return;
  // over the quadratic's own points: the outer ones, a quartic's least weighted, misfit the most
  // and say least about its value at the centre
  double quartic_misfit = 0;
  for (std::size_t j = 0; j < got_quadratic; ++j)
    quartic_misfit = std::max(quartic_misfit, std::abs(uvw[j].z() - quartic_basis(uvw[j].x(), uvw[j].y()).dot(c)) -
                                                  explained(idx[j]));
  keep_better(c[0], Eigen::Vector3d(-c[1] / h, -c[2] / h, 1.0).normalized(), quartic_misfit, z, normal, misfit);
}

void HeightFieldModel::Impl::local_quartic_fit(double x, double y, const Eigen::Vector3d& o, const Eigen::Matrix3d& F,
                                               std::size_t got_quadratic, double& z, Eigen::Vector3d& normal,
                                               double& misfit) const {
  std::uint32_t idx[64];
  double d2[64];
  const std::size_t want = std::min<std::size_t>(2 * got_quadratic, 64);
  const std::size_t got = steep_tree().knnSearch(o.data(), want, idx, d2);
  if (got < want) return;
  const double h = std::sqrt(d2[got - 1]) + 1e-12;
  std::array<Eigen::Vector3d, 64> uvw;  // (a, b, w) in units of h about o, frame F
  for (std::size_t j = 0; j < got; ++j) uvw[j] = F.transpose() * (p[idx[j]] - o) / h;
  QuarticBasis c;
  if (!fit_quartic(uvw, got, c)) return;
  const auto quartic = [&c](double a, double b, double& wa, double& wb) { return quartic_at(c, a, b, wa, wb); };
  Eigen::Vector3d P, n;
  if (!point_above(x, y, o, F, h, 1.0, quartic, P, n)) return;
  double quartic_misfit = 0;
  for (std::size_t j = 0; j < got_quadratic; ++j)
    quartic_misfit = std::max(quartic_misfit, h * std::abs(uvw[j].z() - quartic_basis(uvw[j].x(), uvw[j].y()).dot(c)) -
                                                  explained(idx[j]));
  keep_better(P.z(), n, quartic_misfit, z, normal, misfit);
}

// Weighted least squares of z = c0 + c1 u + c2 v + c3 u² + c4 uv + c5 v², (u, v) = (dx, dy)/h,
// Gaussian weights of width h = the farthest neighbour (Lancaster & Šalkauskas, moving least
// squares): the fit for gentle slopes (or where the local fit failed).
void HeightFieldModel::Impl::xy_weights(double x, double y, const std::uint32_t* idx, const double* d2,
                                        std::size_t got, XyWeights& out) const {
  const double h = std::sqrt(d2[got - 1]) + 1e-12;
  out.h = h;
  for (std::size_t j = 0; j < got; ++j) {
    const double u = (xy(idx[j]).x() - x) / h, v = (xy(idx[j]).y() - y) / h;
    Eigen::Matrix<double, 6, 1>& b = out.basis[j];
    b << 1, u, v, u * u, u * v, v * v;
    out.w[j] = std::exp(-2.0 * (b[3] + b[5]));
  }
}

bool HeightFieldModel::Impl::surely_gentle(const std::uint32_t* idx, std::size_t got, const XyWeights& xw) const {
  // The weighted covariance C of the points; only its xy block and C_zz are asked.
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double wsum = 0;
  for (std::size_t j = 0; j < got; ++j) c += xw.w[j] * p[idx[j]], wsum += xw.w[j];
  c /= wsum;
  double cxx = 0, cyy = 0, cxy = 0, czz = 0;
  for (std::size_t j = 0; j < got; ++j) {
    const Eigen::Vector3d d = p[idx[j]] - c;
    const double w = xw.w[j];
    cxx += w * d.x() * d.x(), cyy += w * d.y() * d.y(), cxy += w * d.x() * d.y(), czz += w * d.z() * d.z();
  }
  // For the least-variance direction n at an angle t from +z: sin^2 t <= C_zz / (mu - C_zz), mu
  // the smaller eigenvalue of C's xy block (Rayleigh quotients and Cauchy interlacing);
  // sin^2 t < 0.3 gives n_z > 0.83 > 0.8, local_fit's own test.
  const double mu = 0.5 * (cxx + cyy) - std::hypot(0.5 * (cxx - cyy), cxy);
  return mu > czz && czz < 0.3 * (mu - czz);
}

bool HeightFieldModel::Impl::xy_fit(const std::uint32_t* idx, std::size_t got, const XyWeights& xw, double& z_out,
                                    Eigen::Vector3d& n_out, double& misfit) const {
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  for (std::size_t j = 0; j < got; ++j) {
    add_weighted_outer_lower(M, xw.basis[j], xw.w[j]);
    rhs += xw.w[j] * p[idx[j]].z() * xw.basis[j];
  }
  Eigen::Matrix<double, 6, 1> c;
  if (!solve_positive_definite(M, rhs, c, 1e-10)) {  // degenerate neighbourhood (collinear points): a plane
    const Eigen::Matrix3d M3 = M.topLeftCorner<3, 3>();
    const Eigen::Vector3d rhs3 = rhs.head<3>();
    Eigen::Vector3d c3;
    if (!solve_positive_definite(M3, rhs3, c3, 0.0)) return false;
    c.setZero();
    c.head<3>() = c3;
  }
  misfit = 0;
  for (std::size_t j = 0; j < got; ++j)
    misfit = std::max(misfit, std::abs(p[idx[j]].z() - xw.basis[j].dot(c)) - explained(idx[j]));
  z_out = c[0];
  n_out = Eigen::Vector3d(-c[1] / xw.h, -c[2] / xw.h, 1.0).normalized();
  return true;
}

}  // namespace scallop
