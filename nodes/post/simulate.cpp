#include "nodes/post/simulate.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <numeric>
#include <stdexcept>
#include "nodes/cloud/kd_tree.h"

namespace scallop {
namespace {

constexpr double kAngle = 0.3;                 // grid rotation (rad), as verify.py ...
constexpr double kPhaseU = 0.37, kPhaseV = 0.71;  // ... and its shift, in spacings
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();


// Every index within a radius, unsorted (cheaper than nanoflann's sorted radiusSearch).
struct CollectAll {
  double radius;  // squared
  std::vector<std::uint32_t>* out;
  void init() {}
  void clear() { out->clear(); }
  std::size_t size() const { return out->size(); }
  bool full() const { return true; }
  bool addPoint(double d, std::uint32_t i) {
    if (d < radius) out->push_back(i);
    return true;
  }
  double worstDist() const { return radius; }
};

// First t >= 0 at which the ray o + t·d (|d| = 1) is within r of the segment [a, b]; +inf if
// never. The capsule is the union of a finite cylinder and two balls; the flat ends of the
// cylinder lie inside the balls, so the first entry is the least of the side entry (when its
// foot falls on the segment) and the two ball entries. The ray starts outside the capsule.
double capsule_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, double r) {
  double best = INFINITY;
  auto ball = [&](const Eigen::Vector3d& c) {
    Eigen::Vector3d oc = o - c;
    double bb = oc.dot(d), cc = oc.squaredNorm() - r * r;
    double disc = bb * bb - cc;
    if (disc < 0) return;
    double t = -bb - std::sqrt(disc);
    if (t >= 0) best = std::min(best, t);
  };
  ball(a);
  ball(b);
  Eigen::Vector3d e = b - a;
  double ee = e.squaredNorm();
  if (ee > 0) {
    Eigen::Vector3d w = o - a;
    double ed = e.dot(d), ew = e.dot(w);
    // |w + t d − ((ew + t ed)/ee) e|² = r²  →  A t² + 2 B t + C = 0
    double A = ee - ed * ed, B = ee * w.dot(d) - ew * ed, C = ee * w.squaredNorm() - ew * ew - r * r * ee;
    if (A > 1e-12 * ee) {
      double disc = B * B - A * C;
      if (disc >= 0) {
        double s = std::sqrt(disc);
        double t = B > 0 ? (-B - s) / A : C / (-B + s);  // the smaller root, without cancellation
        if (t >= 0) {
          double f = ew + t * ed;
          if (f >= 0 && f <= ee) best = std::min(best, t);
        }
      }
    }
  }
  return best;
}

double segment_distance(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Vector3d e = b - a;
  double ee = e.squaredNorm();
  double t = ee > 0 ? std::clamp((q - a).dot(e) / ee, 0.0, 1.0) : 0.0;
  return (a + t * e - q).norm();
}

// Pieces of the centre polyline no longer than `piece`, with a k-d tree over their midpoints.
struct PieceIndex {
  std::vector<Eigen::Vector3d> a, b, mid;
  double half = 0;
  std::unique_ptr<PointsAdaptor<Eigen::Vector3d>> adaptor;
  std::unique_ptr<KdTree<Eigen::Vector3d, 3>> tree;

  PieceIndex(const std::vector<CentreSegment>& segs, double piece) {
    for (const auto& s : segs) {
      double L = (s.b - s.a).norm();
      int k = std::max(1, static_cast<int>(std::ceil(L / piece)));
      for (int j = 0; j < k; ++j) {
        a.push_back(s.a + (s.b - s.a) * (double(j) / k));
        b.push_back(s.a + (s.b - s.a) * (double(j + 1) / k));
        mid.push_back(0.5 * (a.back() + b.back()));
        half = std::max(half, 0.5 * L / k);
      }
    }
    adaptor = std::make_unique<PointsAdaptor<Eigen::Vector3d>>(PointsAdaptor<Eigen::Vector3d>{mid});
    tree = std::make_unique<KdTree<Eigen::Vector3d, 3>>(3, *adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree->buildIndex();
  }

  // gouge and scallop (NaN: uncut) at p with normal n, where the real surface may lie up to
  // `delta` off p either way: the gouge is then at most r - d(p) + delta, the scallop at most
  // its value at p plus delta (the ray from p - delta n reaches p after delta). Every piece that
  // comes within r of the ray segment [p, p + T n] has its midpoint within r + T/2 + half of the
  // ray's middle, so the candidates are complete and, for delta = 0, both values exact.
  void trace(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double r, double T, double delta,
             double& gouge, double& scallop, std::vector<std::uint32_t>& cand) const {
    Eigen::Vector3d m = p + 0.5 * T * n;
    double R = r + 0.5 * T + half;
    CollectAll rs{R * R, &cand};
    cand.clear();
    tree->findNeighbors(rs, m.data(), nanoflann::SearchParams(32, 0, false));
    double d = INFINITY;
    for (auto i : cand) d = std::min(d, segment_distance(p, a[i], b[i]));
    gouge = std::max(0.0, r - d + delta);
    if (d <= r) {
      scallop = std::max(0.0, delta - (r - d));
      return;
    }
    double t = INFINITY;
    for (auto i : cand) t = std::min(t, capsule_entry(p, n, a[i], b[i], r));
    scallop = t <= T ? t + delta : kNaN;
  }
};

struct WeightedStats {
  double max = kNaN, p99 = kNaN, mean = kNaN;
};

WeightedStats weighted_stats(std::vector<std::pair<double, double>> vw) {
  WeightedStats s;
  if (vw.empty()) return s;
  std::sort(vw.begin(), vw.end());
  double total = 0, sum = 0;
  for (auto& [v, w] : vw) total += w, sum += v * w;
  s.max = vw.back().first;
  s.mean = total > 0 ? sum / total : kNaN;
  double acc = 0;
  s.p99 = vw.back().first;
  for (auto& [v, w] : vw) {
    acc += w;
    if (acc / total >= 0.99) {
      s.p99 = v;
      break;
    }
  }
  return s;
}

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

// ----------------------------------------------------------------------------- path centres
std::vector<CentreSegment> feed_centres(const Toolpath& path) {
  std::vector<CentreSegment> out;
  for (const auto& pass : path.passes) {
    if (pass.normal.size() != pass.contact.size())
      throw std::invalid_argument("a pass has " + std::to_string(pass.contact.size()) + " points but " +
                                  std::to_string(pass.normal.size()) + " normals");
    for (std::size_t i = 0; i + 1 < pass.contact.size(); ++i)
      out.push_back({path.centre(pass.contact[i], pass.normal[i]),
                     path.centre(pass.contact[i + 1], pass.normal[i + 1])});
  }
  return out;
}

std::vector<CentreSegment> feed_centres(const LinkedPath& path, double& rapid_length) {
  std::vector<CentreSegment> out;
  rapid_length = 0;
  const Eigen::Vector3d up(0, 0, path.tool_radius);
  for (std::size_t i = 1; i < path.moves.size(); ++i) {
    const auto& m0 = path.moves[i - 1];
    const auto& m1 = path.moves[i];
    if (m1.kind == MoveKind::Rapid)
      rapid_length += (m1.tip - m0.tip).norm();
    else
      out.push_back({m0.tip + up, m1.tip + up});
  }
  return out;
}

// ----------------------------------------------------------------------------- height field
struct HeightField::Impl {
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> z;
  std::vector<Eigen::Vector3d> p;  // the points in 3-D, for the local-frame fit
  std::unique_ptr<PointsAdaptor<Eigen::Vector2d>> adaptor;
  std::unique_ptr<KdTree<Eigen::Vector2d, 2>> tree;
  std::unique_ptr<PointsAdaptor<Eigen::Vector3d>> adaptor3;
  std::unique_ptr<KdTree<Eigen::Vector3d, 3>> tree3;
  std::vector<double> uncertainty;  // per point (mm), or empty

  // The mean uncertainty of the points idx[0..got) (0 without uncertainties).
  double mean_uncertainty(const std::uint32_t* idx, std::size_t got) const;
  bool local_fit(double x, double y, const std::uint32_t* idx, std::size_t got, int k, double& z,
                 Eigen::Vector3d& normal) const;
};

namespace {

// Weighted centroid and unit normal (least-variance direction, turned up) of points `idx`,
// Gaussian weights of width h about o. False when the normal is within ~1 degree of horizontal
// (a wall: no height there) or the points are degenerate.
bool local_plane(const std::vector<Eigen::Vector3d>& P, const std::uint32_t* idx, std::size_t got,
                 const Eigen::Vector3d& o, double h, Eigen::Vector3d& centroid, Eigen::Matrix3d& frame) {
  double wsum = 0;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  std::vector<double> w(got);
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

}  // namespace

// Moving least squares in a local frame (tangent plane of the neighbours, normal w): w(a, b) a
// quadratic, fitted to the k points nearest in 3-D to the current estimate, then the point of it
// above (x, y) found by Newton's method. Unlike a fit of z over (x, y), it stays accurate where
// the surface is steep and the neighbours crowd together in xy (rings of a sphere near its rim
// project onto nearly the same xy lines, and a quadratic in (x, y) through them is ill-posed).
bool HeightField::Impl::local_fit(double x, double y, const std::uint32_t* idx_xy, std::size_t got_xy,
                                  int k, double& z_out, Eigen::Vector3d& n_out) const {
  Eigen::Vector3d m;
  Eigen::Matrix3d F;
  double hxy = 0;
  for (std::size_t j = 0; j < got_xy; ++j) hxy = std::max(hxy, (xy[idx_xy[j]] - Eigen::Vector2d(x, y)).norm());
  // First estimate: the plane through the points nearest to the vertical line at (x, y).
  Eigen::Vector3d o(x, y, 0);
  {
    // weights only on the xy distance here: the z spread is what is unknown
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double wsum = 0;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    std::vector<double> w(got_xy);
    for (std::size_t j = 0; j < got_xy; ++j) {
      w[j] = std::exp(-2.0 * (xy[idx_xy[j]] - Eigen::Vector2d(x, y)).squaredNorm() / (hxy * hxy + 1e-300));
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
  for (int round = 0; round < 3; ++round) {
    const std::size_t got = tree3->knnSearch(o.data(), kk, idx, d2);
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
      M.selfadjointView<Eigen::Lower>().rankUpdate(b, w);
      rhs += w * l.z() * b;
    }
    M.triangularView<Eigen::Upper>() = M.transpose();
    auto ldlt = M.ldlt();
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-8)) return false;
    const Eigen::Matrix<double, 6, 1> c = ldlt.solve(rhs);
    if (!c.allFinite()) return false;
    // Newton on (a, b): the xy of o + h (a t1 + b t2 + w(a, b) n) must be (x, y).
    double a = 0, b = 0;
    Eigen::Vector3d P, ta, tb;
    bool conv = false;
    for (int it = 0; it < 20; ++it) {
      const double w = c[0] + c[1] * a + c[2] * b + c[3] * a * a + c[4] * a * b + c[5] * b * b;
      const double wa = c[1] + 2 * c[3] * a + c[4] * b, wb = c[2] + c[4] * a + 2 * c[5] * b;
      P = o + h * (a * F.col(0) + b * F.col(1) + w * F.col(2));
      ta = F.col(0) + wa * F.col(2);
      tb = F.col(1) + wb * F.col(2);
      const Eigen::Vector2d res(P.x() - x, P.y() - y);
      if (res.norm() < 1e-12 * (1 + h)) {
        conv = true;
        break;
      }
      Eigen::Matrix2d J;
      J << ta.x(), tb.x(), ta.y(), tb.y();
      J *= h;
      if (!(std::abs(J.determinant()) > 1e-12 * h * h)) return false;
      const Eigen::Vector2d step = J.inverse() * res;
      a -= step.x();
      b -= step.y();
      if (std::abs(a) > 3 || std::abs(b) > 3) return false;  // left the neighbourhood
    }
    if (!conv) return false;
    Eigen::Vector3d n = ta.cross(tb).normalized();
    if (n.z() < 0) n = -n;
    const double moved = (P - o).norm();
    o = P;
    z_out = P.z();
    n_out = n;
    if (moved < 0.05 * h) return true;  // the neighbourhood is centred on the point found
  }
  return true;
}

HeightField::HeightField(const std::vector<Eigen::Vector3d>& P, int k,
                         const std::vector<double>* uncertainty)
    : impl_(new Impl), k_(k) {
  if (P.size() < 10) {
    delete impl_;
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; the surface model needs at least 10");
  }
  if (uncertainty && uncertainty->size() != P.size()) {
    delete impl_;
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) + " points but " +
                                std::to_string(uncertainty->size()) + " uncertainties");
  }
  if (uncertainty) {
    impl_->uncertainty = *uncertainty;
    for (double u : *uncertainty) uncertainty_max_ = std::max(uncertainty_max_, u);
  }
  k_ = std::min<int>(k, static_cast<int>(P.size()));
  impl_->xy.reserve(P.size());
  lo_ = Eigen::Vector2d(INFINITY, INFINITY);
  hi_ = -lo_;
  zmax_ = -INFINITY;
  for (const auto& p : P) {
    if (!p.allFinite()) {
      delete impl_;
      throw std::invalid_argument("the cloud has a non-finite point");
    }
    impl_->xy.emplace_back(p.x(), p.y());
    impl_->z.push_back(p.z());
    impl_->p.push_back(p);
    lo_ = lo_.cwiseMin(impl_->xy.back());
    hi_ = hi_.cwiseMax(impl_->xy.back());
    zmax_ = std::max(zmax_, p.z());
  }
  impl_->adaptor = std::make_unique<PointsAdaptor<Eigen::Vector2d>>(PointsAdaptor<Eigen::Vector2d>{impl_->xy});
  impl_->tree = std::make_unique<KdTree<Eigen::Vector2d, 2>>(2, *impl_->adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  impl_->tree->buildIndex();
  impl_->adaptor3 = std::make_unique<PointsAdaptor<Eigen::Vector3d>>(PointsAdaptor<Eigen::Vector3d>{impl_->p});
  impl_->tree3 = std::make_unique<KdTree<Eigen::Vector3d, 3>>(3, *impl_->adaptor3, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  impl_->tree3->buildIndex();
  // Mean spacing from the 8th-neighbour distance: in a uniform sample of density ρ, π ρ r₈² ≈ 8.
  const std::size_t n = P.size(), stride = std::max<std::size_t>(1, n / 2000);
  std::vector<double> r8;
  const int kk = std::min<int>(9, static_cast<int>(n));
  std::vector<std::uint32_t> idx(kk);
  std::vector<double> d2(kk);
  for (std::size_t i = 0; i < n; i += stride) {
    std::size_t got = impl_->tree->knnSearch(impl_->xy[i].data(), kk, idx.data(), d2.data());
    r8.push_back(std::sqrt(d2[got - 1]));
  }
  std::nth_element(r8.begin(), r8.begin() + r8.size() / 2, r8.end());
  spacing_ = r8[r8.size() / 2] * std::sqrt(3.14159265358979 / (kk - 1));
}

HeightField::~HeightField() { delete impl_; }

double HeightField::Impl::mean_uncertainty(const std::uint32_t* idx, std::size_t got) const {
  if (uncertainty.empty() || got == 0) return 0;
  double sum = 0;
  for (std::size_t j = 0; j < got; ++j) sum += uncertainty[idx[j]];
  return sum / got;
}

double HeightField::uncertainty(double x, double y) const {
  std::uint32_t idx[64];
  double d2[64];
  const double q[2] = {x, y};
  return impl_->mean_uncertainty(idx, impl_->tree->knnSearch(q, std::min(k_, 64), idx, d2));
}

bool HeightField::inside(double x, double y) const {
  double z;
  Eigen::Vector3d n;
  return eval(x, y, z, n);
}

bool HeightField::eval(double x, double y, double& z, Eigen::Vector3d& normal, bool force,
                       double* uncertainty) const {
  const int k = k_;
  std::uint32_t idx[64];
  double d2[64];
  const double q[2] = {x, y};
  std::size_t got = impl_->tree->knnSearch(q, std::min(k, 64), idx, d2);
  if (got == 0) return false;
  if (uncertainty) *uncertainty = impl_->mean_uncertainty(idx, got);
  if (!force) {
    if (d2[0] > 2.25 * spacing_ * spacing_) return false;
    // Beyond the edge of the cloud the neighbours are all on one side: their centroid moves
    // off (x, y) by about 0.42 of their radius already at the edge (half a disc).
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (std::size_t j = 0; j < got; ++j) c += impl_->xy[idx[j]];
    c /= double(got);
    if ((c - Eigen::Vector2d(x, y)).squaredNorm() > 0.25 * d2[got - 1]) return false;
  }
  // Steep places: a fit in the local tangent frame (see local_fit).
  if (impl_->local_fit(x, y, idx, got, k, z, normal)) return true;
  // Gentle slopes (or a failed local fit): weighted least squares of z = c0 + c1 u + c2 v + c3 u² + c4 uv + c5 v², (u, v) = (dx, dy)/h,
  // Gaussian weights of width h = the farthest neighbour (Lancaster & Šalkauskas, moving least squares).
  double h = std::sqrt(d2[got - 1]) + 1e-12;
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  for (std::size_t j = 0; j < got; ++j) {
    const auto& p = impl_->xy[idx[j]];
    double u = (p.x() - x) / h, v = (p.y() - y) / h;
    double w = std::exp(-2.0 * (u * u + v * v));
    Eigen::Matrix<double, 6, 1> b;
    b << 1, u, v, u * u, u * v, v * v;
    M.selfadjointView<Eigen::Lower>().rankUpdate(b, w);
    rhs += w * impl_->z[idx[j]] * b;
  }
  M.triangularView<Eigen::Upper>() = M.transpose();
  Eigen::Matrix<double, 6, 1> c;
  auto ldlt = M.ldlt();
  bool ok = ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-10;
  if (ok) c = ldlt.solve(rhs);
  if (!ok || !c.allFinite()) {  // degenerate neighbourhood (collinear points): a plane
    Eigen::Matrix3d M3 = M.topLeftCorner<3, 3>();
    Eigen::Vector3d c3 = M3.ldlt().solve(rhs.head<3>());
    if (!c3.allFinite()) return false;
    c.setZero();
    c.head<3>() = c3;
  }
  z = c[0];
  normal = Eigen::Vector3d(-c[1] / h, -c[2] / h, 1.0).normalized();
  return true;
}

// ----------------------------------------------------------------------------- simulation
SimulationResult simulate_cut(const HeightField& surf, const std::vector<CentreSegment>& feed,
                              double rapid_length, const SimulateOptions& o,
                              const std::function<void(double)>& progress) {
  const double r = o.tool_radius, H = o.scallop;
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(H > 0)) throw std::invalid_argument("scallop limit must be > 0");
  if (feed.empty()) throw std::invalid_argument("the path has no feed moves");
  for (const auto& s : feed)
    if (!s.a.allFinite() || !s.b.allFinite()) throw std::invalid_argument("the path has a non-finite point");
  const bool use_loops = !o.loops.empty();
  if (use_loops) {
    if (o.loops[0].size() < 3)
      throw std::invalid_argument("the outer loop has " + std::to_string(o.loops[0].size()) +
                                  " points; an outline needs at least 3");
    for (const auto& L : o.loops)
      for (const auto& q : L)
        if (!q.allFinite()) throw std::invalid_argument("a loop has a non-finite point");
  }
  const double stepover = std::sqrt(8 * r * H);
  const double margin = o.margin > 0 ? o.margin : stepover;
  const double gouge_tol = std::max(o.chord, 1e-3);
  const double T = 20 * H;
  double spacing = o.spacing > 0 ? o.spacing : stepover / 12;
  {
    // Keep the grid over the cloud's bounding box within max_samples.
    double area = (surf.max_x() - surf.min_x()) * (surf.max_y() - surf.min_y());
    if (o.spacing <= 0 && area / (spacing * spacing) > double(o.max_samples))
      spacing = std::sqrt(area / double(o.max_samples));
  }

  // Grid in (u, v), rotated by kAngle about the centre of the cloud's bounding box.
  const double cx = 0.5 * (surf.min_x() + surf.max_x()), cy = 0.5 * (surf.min_y() + surf.max_y());
  const double Rg = 0.5 * std::hypot(surf.max_x() - surf.min_x(), surf.max_y() - surf.min_y()) + 3 * spacing;
  const double ca = std::cos(kAngle), sa = std::sin(kAngle);
  const int nu = static_cast<int>(std::ceil(2 * Rg / spacing));
  auto to_xy = [&](double u, double v) { return Eigen::Vector2d(cx + ca * u - sa * v, cy + sa * u + ca * v); };
  auto grid_u = [&](int i) { return -Rg + (i + kPhaseU) * spacing; };
  auto grid_v = [&](int j) { return -Rg + (j + kPhaseV) * spacing; };

  struct Raw {
    Eigen::Vector3d p, n;
    double w;
    double u;  // the surface's uncertainty there (mm)
  };
  // Which grid nodes fall on the patch; holes in the cloud (not connected to the outside of the
  // grid through other missing nodes) are part of the patch too.
  std::vector<std::uint8_t> inside(std::size_t(nu) * nu, 0);
  if (use_loops) {
    // Scanline fill with the even-odd rule over all loops at once (inside the outer loop and
    // outside the holes): per grid row, the u where each polygon edge crosses the row's v,
    // sorted; grid nodes between the 1st and 2nd, 3rd and 4th ... crossing are inside.
    std::vector<std::array<double, 4>> edges;  // (u0, v0, u1, v1) in grid coordinates
    for (const auto& L : o.loops)
      for (std::size_t k = 0; k < L.size(); ++k) {
        const Eigen::Vector2d a = L[k] - Eigen::Vector2d(cx, cy), b = L[(k + 1) % L.size()] - Eigen::Vector2d(cx, cy);
        edges.push_back({ca * a.x() + sa * a.y(), -sa * a.x() + ca * a.y(), ca * b.x() + sa * b.y(), -sa * b.x() + ca * b.y()});
      }
    tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
      std::vector<double> cross;
      for (int j = rg.begin(); j < rg.end(); ++j) {
        const double v = grid_v(j);
        cross.clear();
        for (const auto& e : edges)
          if ((e[1] <= v) != (e[3] <= v)) cross.push_back(e[0] + (v - e[1]) / (e[3] - e[1]) * (e[2] - e[0]));
        std::sort(cross.begin(), cross.end());
        for (std::size_t c = 0; c + 1 < cross.size(); c += 2) {
          // grid_u(i) = -Rg + (i + kPhaseU) spacing; nodes with cross[c] <= u < cross[c+1]
          const int i0 = std::max(0, static_cast<int>(std::ceil((cross[c] + Rg) / spacing - kPhaseU)));
          const int i1 = std::min(nu - 1, static_cast<int>(std::ceil((cross[c + 1] + Rg) / spacing - kPhaseU)) - 1);
          for (int i = i0; i <= i1; ++i) inside[std::size_t(j) * nu + i] = 1;
        }
      }
    });
  } else {
  tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
    for (int j = rg.begin(); j < rg.end(); ++j)
      for (int i = 0; i < nu; ++i) {
        Eigen::Vector2d q = to_xy(grid_u(i), grid_v(j));
        if (q.x() < surf.min_x() - spacing || q.x() > surf.max_x() + spacing || q.y() < surf.min_y() - spacing ||
            q.y() > surf.max_y() + spacing)
          continue;
        inside[std::size_t(j) * nu + i] = surf.inside(q.x(), q.y());
      }
  });
  {
    std::vector<std::uint8_t> outside(inside.size(), 0);
    std::vector<std::size_t> stack;
    for (int i = 0; i < nu; ++i)
      for (std::size_t id : {std::size_t(i), std::size_t(nu - 1) * nu + i, std::size_t(i) * nu, std::size_t(i) * nu + nu - 1})
        if (!inside[id] && !outside[id]) outside[id] = 1, stack.push_back(id);
    while (!stack.empty()) {
      std::size_t id = stack.back();
      stack.pop_back();
      int i = int(id % nu), j = int(id / nu);
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int t = 0; t < 4; ++t) {
        int ii = i + di[t], jj = j + dj[t];
        if (ii < 0 || jj < 0 || ii >= nu || jj >= nu) continue;
        std::size_t nid = std::size_t(jj) * nu + ii;
        if (!inside[nid] && !outside[nid]) outside[nid] = 1, stack.push_back(nid);
      }
    }
    for (std::size_t id = 0; id < inside.size(); ++id) inside[id] = !outside[id];
  }
  }

  std::vector<std::vector<Raw>> rows(nu);
  tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
    for (int j = rg.begin(); j < rg.end(); ++j) {
      for (int i = 0; i < nu; ++i) {
        if (!inside[std::size_t(j) * nu + i]) continue;
        Eigen::Vector2d q = to_xy(grid_u(i), grid_v(j));
        double z, u;
        Eigen::Vector3d n;
        if (!surf.eval(q.x(), q.y(), z, n, true, &u)) continue;
        // Steep cells are split k×k so the spacing along the surface stays near `spacing`.
        int k = std::clamp(static_cast<int>(std::lround(1.0 / n.z())), 1, 4);
        if (k == 1) {
          rows[j].push_back({{q.x(), q.y(), z}, n, spacing * spacing / n.z(), u});
          continue;
        }
        for (int a = 0; a < k; ++a)
          for (int b = 0; b < k; ++b) {
            Eigen::Vector2d s = to_xy(grid_u(i) + ((a + 0.5) / k - 0.5) * spacing,
                                      grid_v(j) + ((b + 0.5) / k - 0.5) * spacing);
            double zs, us;
            Eigen::Vector3d ns;
            if (surf.eval(s.x(), s.y(), zs, ns, true, &us))
              rows[j].push_back({{s.x(), s.y(), zs}, ns, spacing * spacing / (k * k * ns.z()), us});
          }
      }
    }
  });
  std::vector<Raw> raw;
  for (auto& row : rows) raw.insert(raw.end(), row.begin(), row.end());
  rows.clear();
  if (raw.empty()) throw std::invalid_argument("no grid sample falls on the surface");
  if (progress) progress(0.1);

  // Outline: grid nodes outside the patch next to one inside; interior = farther than the margin.
  std::vector<Eigen::Vector2d> outline;
  for (int j = 0; j < nu; ++j)
    for (int i = 0; i < nu; ++i) {
      if (inside[std::size_t(j) * nu + i]) continue;
      bool near = false;
      for (int dj = -1; dj <= 1 && !near; ++dj)
        for (int di = -1; di <= 1 && !near; ++di) {
          int ii = i + di, jj = j + dj;
          near = ii >= 0 && jj >= 0 && ii < nu && jj < nu && inside[std::size_t(jj) * nu + ii];
        }
      if (near) outline.push_back(to_xy(grid_u(i), grid_v(j)));
    }
  // With loops the margin is measured from their edges, resampled every quarter spacing (the
  // nearest resampled point is at most an eighth of a spacing farther than the edge).
  std::vector<Eigen::Vector2d> edge_points;
  if (use_loops)
    for (const auto& L : o.loops)
      for (std::size_t k = 0; k < L.size(); ++k) {
        const Eigen::Vector2d a = L[k], b = L[(k + 1) % L.size()];
        const int m = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.25 * spacing))));
        for (int t = 0; t < m; ++t) edge_points.push_back(a + (b - a) * (double(t) / m));
      }
  const std::vector<Eigen::Vector2d>& edge_set = use_loops ? edge_points : outline;
  PointsAdaptor<Eigen::Vector2d> outline_adaptor{edge_set};
  KdTree<Eigen::Vector2d, 2> outline_tree(2, outline_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  outline_tree.buildIndex();
  // The outline nodes lie up to a spacing outside the patch: measure from half a spacing in.
  const double edge_offset = use_loops ? 0.0 : 0.5 * spacing;
  auto is_interior = [&](double x, double y) {
    if (edge_set.empty()) return true;
    std::uint32_t i;
    double d2;
    double q[2] = {x, y};
    outline_tree.knnSearch(q, 1, &i, &d2);
    return std::sqrt(d2) - edge_offset > margin;
  };
  // With loops, a refinement sample is on the patch when its nearest grid node is.
  auto on_patch_grid = [&](double x, double y) {
    const double dx = x - cx, dy = y - cy, u = ca * dx + sa * dy, v = -sa * dx + ca * dy;
    const long i = std::lround((u + Rg) / spacing - kPhaseU), j = std::lround((v + Rg) / spacing - kPhaseV);
    return i >= 0 && j >= 0 && i < nu && j < nu && inside[std::size_t(j) * nu + std::size_t(i)];
  };

  std::vector<double> lengths;
  double cut_length = 0;
  for (const auto& s : feed) lengths.push_back((s.b - s.a).norm()), cut_length += lengths.back();
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() * 9 / 10, lengths.end());
  const double piece = std::clamp(lengths[lengths.size() * 9 / 10], spacing, std::max(spacing, r / 2));
  PieceIndex index(feed, piece);

  SimulationResult res;
  res.spacing = spacing;
  res.samples.resize(raw.size());
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, raw.size(), 1024), [&](const tbb::blocked_range<std::size_t>& rg) {
    std::vector<std::uint32_t> cand;
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
      const Raw& s = raw[i];
      SimSample& out = res.samples[i];
      out.x = s.p.x(), out.y = s.p.y(), out.z = s.p.z(), out.weight = s.w;
      index.trace(s.p, s.n, r, T, s.u, out.gouge, out.scallop, cand);
      out.interior = is_interior(s.p.x(), s.p.y());
    }
    std::size_t d = done.fetch_add(rg.size()) + rg.size();
    if (progress) progress(0.1 + 0.7 * double(d) / raw.size());
  });
  const std::size_t n_grid = res.samples.size();
  bool no_interior = std::none_of(res.samples.begin(), res.samples.end(), [](const SimSample& s) { return s.interior; });
  if (no_interior)
    for (auto& s : res.samples) s.interior = true;

  // Local refinement around the highest values (verify.py's levels: seeds, half-width/spacing).
  const std::pair<int, double> levels[] = {{1000, 1.0}, {100, 0.25}, {30, 1.0 / 16}};
  for (auto [K, halfw] : levels) {
    std::vector<std::size_t> seeds;
    auto top = [&](auto value, auto keep, int count) {
      std::vector<std::size_t> c;
      for (std::size_t i = 0; i < res.samples.size(); ++i)
        if (keep(res.samples[i]) && value(res.samples[i]) > 0) c.push_back(i);
      if (int(c.size()) > count)
        std::nth_element(c.begin(), c.begin() + count, c.end(),
                         [&](auto a, auto b) { return value(res.samples[a]) > value(res.samples[b]); }),
            c.resize(count);
      seeds.insert(seeds.end(), c.begin(), c.end());
    };
    auto sc = [](const SimSample& s) { return std::isnan(s.scallop) ? -1.0 : s.scallop; };
    auto go = [](const SimSample& s) { return s.gouge; };
    top(sc, [](const SimSample& s) { return s.interior; }, K);
    top(sc, [](const SimSample&) { return true; }, K / 4);
    top(go, [](const SimSample&) { return true; }, K / 4);
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    if (seeds.empty()) break;
    const int m = 4;  // (2m+1)² points per seed
    std::vector<SimSample> extra(seeds.size() * (2 * m + 1) * (2 * m + 1));
    std::vector<std::uint8_t> valid(extra.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size()), [&](const tbb::blocked_range<std::size_t>& rg) {
      std::vector<std::uint32_t> cand;
      for (std::size_t si = rg.begin(); si < rg.end(); ++si) {
        const SimSample c = res.samples[seeds[si]];
        for (int a = -m; a <= m; ++a)
          for (int b = -m; b <= m; ++b) {
            double du = halfw * spacing * a / m, dv = halfw * spacing * b / m;
            double x = c.x + ca * du - sa * dv, y = c.y + sa * du + ca * dv, z, u;
            Eigen::Vector3d n;
            std::size_t slot = (si * (2 * m + 1) + (a + m)) * (2 * m + 1) + (b + m);
            if (use_loops ? !(on_patch_grid(x, y) && surf.eval(x, y, z, n, true, &u))
                          : !surf.eval(x, y, z, n, false, &u))
              continue;
            SimSample& out = extra[slot];
            out.x = x, out.y = y, out.z = z, out.weight = 0;
            index.trace({x, y, z}, n, r, T, u, out.gouge, out.scallop, cand);
            out.interior = no_interior || is_interior(x, y);
            valid[slot] = 1;
          }
      }
    });
    for (std::size_t i = 0; i < extra.size(); ++i)
      if (valid[i]) res.samples.push_back(extra[i]);
  }
  if (progress) progress(0.95);

  // Statistics: area-weighted over the grid; maxima include the refinement samples.
  auto& rep = res.report;
  double area = 0, area_i = 0, uncut = 0, uncut_i = 0, gouge_max = 0;
  std::vector<std::pair<double, double>> all, inner;
  double max_all = -INFINITY, max_inner = -INFINITY;
  std::size_t n_interior = 0;
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    gouge_max = std::max(gouge_max, s.gouge);
    bool cut = !std::isnan(s.scallop);
    if (cut) {
      max_all = std::max(max_all, s.scallop);
      if (s.interior) max_inner = std::max(max_inner, s.scallop);
    }
    if (i >= n_grid) continue;
    area += s.weight;
    if (s.interior) area_i += s.weight, ++n_interior;
    if (!cut) {
      uncut += s.weight;
      if (s.interior) uncut_i += s.weight;
      continue;
    }
    all.emplace_back(s.scallop, s.weight);
    if (s.interior) inner.emplace_back(s.scallop, s.weight);
  }
  if (!std::isfinite(max_all)) max_all = kNaN;
  if (!std::isfinite(max_inner)) max_inner = kNaN;
  WeightedStats st = weighted_stats(std::move(all)), sti = weighted_stats(std::move(inner));
  rep["tool_radius"] = r;
  rep["scallop_limit"] = H;
  rep["chord_limit"] = o.chord;
  rep["spacing"] = spacing;
  rep["margin"] = margin;
  rep["samples"] = n_grid;
  rep["samples_interior"] = n_interior;
  rep["samples_refined"] = res.samples.size() - n_grid;
  rep["surface_area"] = area;
  rep["scallop_max"] = num(max_all);
  rep["scallop_max_interior"] = num(max_inner);
  rep["scallop_p99"] = num(st.p99);
  rep["scallop_p99_interior"] = num(sti.p99);
  rep["scallop_mean"] = num(st.mean);
  rep["scallop_mean_interior"] = num(sti.mean);
  rep["gouge_max"] = gouge_max;
  rep["uncut_fraction"] = area > 0 ? uncut / area : 0.0;
  rep["uncut_fraction_interior"] = area_i > 0 ? uncut_i / area_i : 0.0;
  rep["cut_length"] = cut_length;
  rep["rapid_length"] = rapid_length;
  // how far the cloud may be off the real surface: scallop and gouge above include it
  rep["surface_uncertainty_max"] = surf.uncertainty_max();

  nlohmann::json reasons = nlohmann::json::array();
  char buf[160];
  if (std::isnan(max_inner)) {
    reasons.push_back("no interior sample was cut");
  } else if (max_inner > 1.01 * H) {
    std::snprintf(buf, sizeof buf, "interior scallop max %.4g > 1.01 H", max_inner);
    reasons.push_back(buf);
  }
  if (gouge_max > gouge_tol) {
    std::snprintf(buf, sizeof buf, "gouge max %.4g > %.4g", gouge_max, gouge_tol);
    reasons.push_back(buf);
  }
  if (uncut > 0) {
    std::snprintf(buf, sizeof buf, "uncut fraction %.4g > 0", uncut / area);
    reasons.push_back(buf);
  }
  rep["pass"] = reasons.empty();
  rep["fail_reasons"] = reasons;

  // The ten worst places, at least a stepover apart: gouges beyond tolerance, then uncut spots,
  // then scallops, each ranked by how far it is over its limit.
  std::vector<std::pair<double, std::size_t>> rank;
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    double score = std::isnan(s.scallop) ? 1e6 : s.scallop / H;
    if (s.gouge > gouge_tol) score = 1e9 + s.gouge / gouge_tol;
    if (score > 0) rank.emplace_back(score, i);
  }
  std::sort(rank.begin(), rank.end(), std::greater<>());
  nlohmann::json worst = nlohmann::json::array();
  std::vector<Eigen::Vector2d> taken;
  for (auto& [score, i] : rank) {
    if (worst.size() >= 10) break;
    const SimSample& s = res.samples[i];
    Eigen::Vector2d q(s.x, s.y);
    if (std::any_of(taken.begin(), taken.end(), [&](const auto& t) { return (t - q).norm() < stepover; })) continue;
    taken.push_back(q);
    std::string kind = s.gouge > gouge_tol ? "gouge" : std::isnan(s.scallop) ? "uncut" : "scallop";
    nlohmann::json v = kind == "gouge" ? nlohmann::json(s.gouge) : kind == "uncut" ? nlohmann::json() : nlohmann::json(s.scallop);
    worst.push_back({{"x", s.x}, {"y", s.y}, {"z", s.z}, {"kind", kind}, {"value", v}, {"interior", s.interior}});
  }
  rep["worst"] = worst;
  res.outline = std::move(outline);
  if (progress) progress(1.0);
  return res;
}

}  // namespace scallop
