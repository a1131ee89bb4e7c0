#include "nodes/geom/bspline_surface.h"

#include <BSplCLib.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <math_Matrix.hxx>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace scallop {

std::vector<double> clamped_uniform_knots(int poles, int degree) {
  if (degree < 1 || poles <= degree) throw std::invalid_argument("clamped_uniform_knots: need 1 <= degree < poles");
  std::vector<double> k(std::size_t(poles + degree + 1), 0.0);
  const int spans = poles - degree;
  for (int i = 1; i < spans; ++i) k[std::size_t(degree + i)] = double(i) / spans;
  std::fill(k.end() - degree - 1, k.end(), 1.0);
  return k;
}

std::vector<double> averaged_knots(int poles, int degree) {
  std::vector<double> k = clamped_uniform_knots(poles, degree);
  // Inner knot j (1 .. poles - degree - 1): the mean of t_j .. t_{j+degree-1}.
  for (int j = 1; j < poles - degree; ++j) k[std::size_t(degree + j)] = (j + (degree - 1) / 2.0) / (poles - 1);
  return k;
}

BasisAt bspline_basis(const std::vector<double>& knots, int degree, double t, int derivatives) {
  if (degree < 1 || degree > kMaxDegree || derivatives < 0 || derivatives > kMaxDegree)
    throw std::invalid_argument("bspline_basis: degree " + std::to_string(degree) + " with " +
                                std::to_string(derivatives) + " derivatives");
  // Views of the knots and of a buffer on the stack, not copies: this runs for every point the
  // planners evaluate, and copying the knots made its cost grow with the patch's size.
  const TColStd_Array1OfReal flat(knots.front(), 1, static_cast<int>(knots.size()));
  double buffer[(kMaxDegree + 1) * (kMaxDegree + 1)];
  math_Matrix m(buffer, 1, derivatives + 1, 1, degree + 1);
  int first = 0;
  // OpenCASCADE's index of the first non-zero function is 1-based.
  if (BSplCLib::EvalBsplineBasis(derivatives, degree + 1, flat, std::clamp(t, 0.0, 1.0), first, m) != 0)
    throw std::runtime_error("bspline_basis: OpenCASCADE could not evaluate the basis at " + std::to_string(t));
  BasisAt b;
  b.first = first - 1;
  b.values.resize(derivatives + 1, degree + 1);
  for (int d = 0; d <= derivatives; ++d)
    for (int k = 0; k <= degree; ++k) b.values(d, k) = m(d + 1, k + 1);
  return b;
}

namespace {

// The bases each thread evaluated lately in u and in v for a patch (BSplinePatch::id_, never
// reused), 32 per direction, each parameter in its own slot (hashed): the planners sample along
// lines of constant u or v, and a strip's check samples the same 9 parameters across it at every
// step along it (one basis remembered per direction was re-evaluated for each of the 9: a fifth
// of the block's contours).
struct BasisMemo {
  std::uint64_t owner = 0;  // 0: empty
  double t = 0;
  BasisAt basis;
};
constexpr std::size_t kMemoSlots = 32;
thread_local std::array<std::array<BasisMemo, kMemoSlots>, 2> basis_memo;
std::atomic<std::uint64_t> next_patch_id{1};

std::size_t memo_slot(double t) {
  std::uint64_t bits;
  std::memcpy(&bits, &t, sizeof bits);
  bits *= 0x9E3779B97F4A7C15ull;  // Fibonacci hashing: the top bits mix every bit of t
  return std::size_t(bits >> 59);  // 5 bits: 0 .. 31
}

// bspline_basis with second derivatives (fewer if the degree is lower), remembered per thread
// for owner != 0 in direction dir (0: u, 1: v).
const BasisAt& basis_with_second(const std::vector<double>& knots, int degree, double t, std::uint64_t owner, int dir,
                                 BasisAt& scratch) {
  if (owner == 0) return scratch = bspline_basis(knots, degree, t, std::min(2, degree));
  BasisMemo& m = basis_memo[dir][memo_slot(t)];
  if (m.owner != owner || m.t != t) m.basis = bspline_basis(knots, degree, t, std::min(2, degree)), m.owner = owner, m.t = t;
  return m.basis;
}

SurfaceJet evaluate_jet(const BSplineSurface& s, double u, double v, int order, std::uint64_t owner) {
  if (order != 1 && order != 2) throw std::invalid_argument("evaluate: order " + std::to_string(order) + " (1 or 2)");
  // The basis always with second derivatives: its lower rows then come out the same either way.
  BasisAt su, sv;
  const BasisAt& bu = basis_with_second(s.knots_u, s.degree_u, u, owner, 0, su);
  const BasisAt& bv = basis_with_second(s.knots_v, s.degree_v, v, owner, 1, sv);
  // The basis rows as plain arrays, zero past the degree's derivatives.
  double wu[3][kMaxDegree + 1] = {}, wv[3][kMaxDegree + 1] = {};
  for (int d = 0; d < std::min<int>(3, int(bu.values.rows())); ++d)
    for (int a = 0; a <= s.degree_u; ++a) wu[d][a] = bu.values(d, a);
  for (int d = 0; d < std::min<int>(3, int(bv.values.rows())); ++d)
    for (int b = 0; b <= s.degree_v; ++b) wv[d][b] = bv.values(d, b);
  SurfaceJet j;
  j.point = j.du = j.dv = j.duu = j.duv = j.dvv = Eigen::Vector3d::Zero();
  // Each row of poles summed along u first (its value and u-derivatives), then the rows along v:
  // half the products of adding every pole into every derivative (a fifth of the contours' time).
  for (int b = 0; b <= s.degree_v; ++b) {
    Eigen::Vector3d row0 = Eigen::Vector3d::Zero(), row1 = Eigen::Vector3d::Zero(), row2 = Eigen::Vector3d::Zero();
    for (int a = 0; a <= s.degree_u; ++a) {
      const Eigen::Vector3d& p = s.pole(static_cast<std::uint32_t>(bu.first + a), static_cast<std::uint32_t>(bv.first + b));
      row0 += wu[0][a] * p, row1 += wu[1][a] * p;
      if (order == 2) row2 += wu[2][a] * p;
    }
    j.point += wv[0][b] * row0, j.du += wv[0][b] * row1, j.dv += wv[1][b] * row0;
    if (order < 2) continue;
    j.duu += wv[0][b] * row2, j.duv += wv[1][b] * row1, j.dvv += wv[2][b] * row0;
  }
  return j;
}

}  // namespace

SurfaceJet evaluate(const BSplineSurface& s, double u, double v, int order) { return evaluate_jet(s, u, v, order, 0); }

Eigen::Vector3d surface_point(const BSplineSurface& s, double u, double v) {
  const BasisAt bu = bspline_basis(s.knots_u, s.degree_u, u, 0);
  const BasisAt bv = bspline_basis(s.knots_v, s.degree_v, v, 0);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int b = 0; b <= s.degree_v; ++b)
    for (int a = 0; a <= s.degree_u; ++a)
      p += bu.values(0, a) * bv.values(0, b) *
           s.pole(static_cast<std::uint32_t>(bu.first + a), static_cast<std::uint32_t>(bv.first + b));
  return p;
}

namespace {
std::string knot_problem(const std::vector<double>& k, int degree, std::uint32_t poles, const char* dir) {
  const std::string d(dir);
  if (degree < 1 || degree > kMaxDegree)
    return "degree in " + d + " is " + std::to_string(degree) + " (1.." + std::to_string(kMaxDegree) + ")";
  if (poles <= static_cast<std::uint32_t>(degree))
    return std::to_string(poles) + " poles in " + d + " for degree " + std::to_string(degree);
  if (k.size() != poles + degree + 1)
    return std::to_string(k.size()) + " knots in " + d + " for " + std::to_string(poles) + " poles of degree " +
           std::to_string(degree);
  for (std::size_t i = 0; i < k.size(); ++i)
    if (!std::isfinite(k[i]) || (i > 0 && k[i] < k[i - 1])) return "knots in " + d + " not increasing at " + std::to_string(i);
  for (int i = 0; i <= degree; ++i)
    if (k[i] != 0.0 || k[k.size() - 1 - i] != 1.0) return "knots in " + d + " not clamped to [0, 1]";
  // Inner multiplicity above the degree would break the surface.
  for (std::size_t i = degree + 1; i + degree + 1 < k.size(); ++i)
    if (k[i] == k[i + degree]) return "a knot in " + d + " repeats more than the degree";
  return "";
}
}  // namespace

std::string bspline_problem(const BSplineSurface& s) {
  if (auto p = knot_problem(s.knots_u, s.degree_u, s.poles_u, "u"); !p.empty()) return p;
  if (auto p = knot_problem(s.knots_v, s.degree_v, s.poles_v, "v"); !p.empty()) return p;
  if (s.poles.size() != std::size_t(s.poles_u) * s.poles_v)
    return std::to_string(s.poles.size()) + " poles for a " + std::to_string(s.poles_u) + " by " +
           std::to_string(s.poles_v) + " net";
  for (const auto& p : s.poles)
    if (!p.allFinite()) return "a pole is not finite";
  return "";
}

BSplinePatch::BSplinePatch(BSplineSurface surface, const Eigen::Vector3d& up, double uncertainty, double min_up_dot)
    : surface_(std::move(surface)), up_(up.normalized()), uncertainty_(uncertainty), min_up_dot_(min_up_dot),
      id_(next_patch_id++) {
  if (const std::string problem = bspline_problem(surface_); !problem.empty())
    throw std::invalid_argument("BSplinePatch: " + problem);
  if (!up_.allFinite()) throw std::invalid_argument("BSplinePatch: the up direction is zero or not finite");
  domain_.kind = UVDomain::Kind::Rectangle;
  domain_.width = domain_.height = 1;
  double span = 1;
  for (const auto* knots : {&surface_.knots_u, &surface_.knots_v})
    for (std::size_t k = 0; k + 1 < knots->size(); ++k)
      if ((*knots)[k + 1] > (*knots)[k]) span = std::min(span, (*knots)[k + 1] - (*knots)[k]);
  spacing_ = span / 4;
}

namespace {
// ru x rv turned to up's side; up where it vanishes.
Eigen::Vector3d jet_normal(const SurfaceJet& j, const Eigen::Vector3d& up) {
  const Eigen::Vector3d n = j.du.cross(j.dv);
  const double scale = j.du.norm() * j.dv.norm();
  const Eigen::Vector3d unit = n.norm() > 1e-12 * scale && scale > 0 ? Eigen::Vector3d(n.normalized()) : up;
  return unit.dot(up) < 0 ? Eigen::Vector3d(-unit) : unit;
}
}  // namespace

SurfaceSample BSplinePatch::sample(const SurfaceJet& j, const Eigen::Vector2d& uv) const {
  SurfaceSample x;
  x.position = j.point;
  x.normal = jet_normal(j, up_);
  if (x.normal.dot(up_) < min_up_dot_) {
    constexpr int kSteps = 64;  // on the way to the centre
    const Eigen::Vector2d centre(0.5, 0.5);
    x.normal = up_;
    for (int k = 1; k <= kSteps; ++k) {
      const Eigen::Vector2d y = uv + (centre - uv) * (double(k) / kSteps);
      if (const Eigen::Vector3d n = jet_normal(evaluate_jet(surface_, y.x(), y.y(), 1, id_), up_); n.dot(up_) >= min_up_dot_) {
        x.normal = n;
        break;
      }
    }
  }
  x.uncertainty = uncertainty_;
  return x;
}

SurfaceDerivatives BSplinePatch::derivatives(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d c = domain_.clamp(uv);
  const SurfaceJet j = evaluate_jet(surface_, c.x(), c.y(), 2, id_);
  SurfaceDerivatives d;
  d.sample = sample(j, c);
  d.ru = j.du, d.rv = j.dv, d.ruu = j.duu, d.ruv = j.duv, d.rvv = j.dvv;
  return d;
}

SurfaceSample BSplinePatch::operator()(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d c = domain_.clamp(uv);
  return sample(evaluate_jet(surface_, c.x(), c.y(), 1, id_), c);
}

}  // namespace scallop
