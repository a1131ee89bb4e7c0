#include "nodes/path/uv_interpolation.h"


#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include "nodes/geom/grid_knn_2d.h"
#include "nodes/geom/normal_equations.h"

namespace scallop {

namespace {

constexpr int kMaxK = 64;

}  // namespace

struct UVInterpolator::Impl {
  const std::vector<Eigen::Vector3d>& P;
  const std::vector<Eigen::Vector3d>& N;
  const std::vector<Eigen::Vector2d>& UV;
  const std::vector<double>* U;  // per-point uncertainty, or null
  GridKnn2d grid;  // exact k nearest in uv (twice as fast here as a k-d tree)
  int k;
  Impl(const std::vector<Eigen::Vector3d>& P_, const std::vector<Eigen::Vector3d>& N_,
       const std::vector<Eigen::Vector2d>& UV_, int k_, const std::vector<double>* U_)
      : P(P_), N(N_), UV(UV_), U(U_), grid(UV_), k(k_) {}
};

UVInterpolator::UVInterpolator(const std::vector<Eigen::Vector3d>& P,
                               const std::vector<Eigen::Vector3d>& N,
                               const std::vector<Eigen::Vector2d>& UV, UVDomain domain, int k,
                               const std::vector<double>* uncertainty)
    : domain_(domain) {
  if (uncertainty && uncertainty->size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) + " points but " +
                                std::to_string(uncertainty->size()) + " uncertainties");
  if (N.size() != P.size() || UV.size() != P.size())
    throw std::invalid_argument("positions, normals and uv differ in count (" +
                                std::to_string(P.size()) + ", " + std::to_string(N.size()) +
                                ", " + std::to_string(UV.size()) + ")");
  if (k < 6 || k > kMaxK)
    throw std::invalid_argument("the interpolation needs 6 to 64 neighbours per fit (got " +
                                std::to_string(k) + ")");
  if (P.size() <= static_cast<std::size_t>(k))
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; interpolation with k = " + std::to_string(k) +
                                " needs at least " + std::to_string(k + 1));
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!P[i].allFinite() || !N[i].allFinite() || !UV[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a NaN or infinite position, normal or uv");
  impl_ = std::make_unique<Impl>(P, N, UV, k, uncertainty);

  // Sampling scale: median nearest-neighbour distance in uv (a subsample is plenty).
  const std::size_t stride = std::max<std::size_t>(1, P.size() / 4096);
  std::vector<double> d;
  for (std::size_t i = 0; i < P.size(); i += stride) {
    std::array<std::uint32_t, 2> idx{};
    std::array<double, 2> dist{};
    if (impl_->grid.query(UV[i], 2, idx.data(), dist.data()) == 2 && dist[1] > 0) d.push_back(std::sqrt(dist[1]));
  }
  if (d.empty()) throw std::invalid_argument("all points have the same uv");
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  uv_spacing_ = d[d.size() / 2];
}

UVInterpolator::~UVInterpolator() = default;

SurfaceSample UVInterpolator::operator()(const Eigen::Vector2d& uv_in) const {
  const Eigen::Vector2d q = domain_.clamp(uv_in);
  const int k = impl_->k;
  std::array<std::uint32_t, kMaxK + 1> idx{};
  std::array<double, kMaxK + 1> sq{};
  const int found = impl_->grid.query(q, k + 1, idx.data(), sq.data());
  const double D2 = sq[found - 1] > 0 ? sq[found - 1] : 1.0;
  const double inv_D = 1.0 / std::sqrt(D2);

  // Weighted normal equations for the quadratic basis in scaled offsets (x, y) = (uv - q) / D,
  // six right-hand sides at once: x, y, z, nx, ny, nz.
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  Mat6 M = Mat6::Zero();
  Eigen::Matrix<double, 6, 6> rhs = Mat6::Zero();
  int used = 0;
  // A soft maximum of the neighbours' uncertainty: the weighted power mean of order 8 leans on
  // the largest values yet stays continuous in uv (the weights vanish at D), so a stock taken
  // from it puts no step into the ball-centre curve.
  double uw = 0, usum = 0, uscale = 0;
  if (impl_->U)
    for (int j = 0; j < found - 1; ++j) uscale = std::max(uscale, (*impl_->U)[idx[j]]);
  for (int j = 0; j < found - 1; ++j) {
    const double w0 = 1 - sq[j] / D2;
    const double w = w0 * w0;
    if (w <= 0) continue;
    ++used;
    if (impl_->U && uscale > 0) {
      uw += w;
      const double x2 = (*impl_->U)[idx[j]] / uscale * ((*impl_->U)[idx[j]] / uscale);
      const double x4 = x2 * x2;
      usum += w * (x4 * x4);
    }
    const Eigen::Vector2d o = (impl_->UV[idx[j]] - q) * inv_D;
    Eigen::Matrix<double, 6, 1> b;
    b << 1, o.x(), o.y(), o.x() * o.x(), o.x() * o.y(), o.y() * o.y();
    Eigen::Matrix<double, 1, 6> f;
    f << impl_->P[idx[j]].transpose(), impl_->N[idx[j]].transpose();
    add_weighted_outer_lower(M, b, w);
    rhs.noalias() += (w * b) * f;
  }
  Eigen::Matrix<double, 1, 6> value;
  // Tangents of the fitted position (per unit of the scaled offsets): their cross product is
  // the normal of the fitted surface itself, which is far more accurate than the interpolated
  // point normals (PCA normals lean by O(spacing x curvature), and the ball centre r n moves
  // r times that sideways).
  Eigen::Vector3d tu = Eigen::Vector3d::Zero(), tv = Eigen::Vector3d::Zero();
  bool ok = false;
  if (used >= 6) {
    Mat6 c;
    if (solve_positive_definite(M, rhs, c, 1e-9)) {
      value = c.row(0);
      tu = c.row(1).head<3>().transpose();
      tv = c.row(2).head<3>().transpose();
      ok = true;
    }
  }
  if (!ok && used >= 3) {
    // Too few or collinear neighbours for a quadric: a plane still has linear precision (the
    // linear basis's equations are the quadric's first three rows and columns).
    const Eigen::Matrix3d M3 = M.topLeftCorner<3, 3>();
    const Eigen::Matrix<double, 3, 6> rhs3 = rhs.topRows<3>();
    Eigen::Matrix<double, 3, 6> c;
    if (solve_positive_definite(M3, rhs3, c, 1e-9)) {
      value = c.row(0);
      tu = c.row(1).head<3>().transpose();
      tv = c.row(2).head<3>().transpose();
      ok = true;
    }
  }
  if (!ok) {  // degenerate neighbourhood: the nearest point
    value << impl_->P[idx[0]].transpose(), impl_->N[idx[0]].transpose();
  }
  SurfaceSample s;
  if (impl_->U) s.uncertainty = uw > 0 ? uscale * std::sqrt(std::sqrt(std::sqrt(usum / uw))) : (*impl_->U)[idx[0]];
  s.position = value.head<3>().transpose();
  Eigen::Vector3d n = value.tail<3>().transpose();
  const double nn = n.norm();
  s.normal = nn > 1e-12 ? Eigen::Vector3d(n / nn) : impl_->N[idx[0]];
  // The fitted surface's own normal, oriented like the interpolated one. Near the domain's edge
  // the fit extrapolates and its tangents are poor, so there it is blended into the point
  // normals (weight 0 within D/4 of the edge, 1 beyond 3D/4, D the fit radius); it is also
  // dropped where the tangents are degenerate or it disagrees with the point normals by more
  // than 10 degrees (a folded fit).
  const Eigen::Vector3d m = tu.cross(tv);
  const double mn = m.norm();
  if (ok && mn > 1e-9 * tu.squaredNorm() + 1e-300) {
    Eigen::Vector3d g = m / mn;
    if (g.dot(s.normal) < 0) g = -g;
    const double edge = domain_.kind == UVDomain::Kind::Rectangle
                            ? std::min({q.x(), domain_.width - q.x(), q.y(), domain_.height - q.y()})
                            : domain_.radius - q.norm();
    const double a = std::clamp((edge * inv_D - 0.25) / 0.5, 0.0, 1.0);
    if (a > 0 && g.dot(s.normal) > std::cos(M_PI / 18))
      s.normal = (a * g + (1 - a) * s.normal).normalized();
  }
  return s;
}

}  // namespace scallop
