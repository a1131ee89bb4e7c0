// Non-rational tensor-product B-spline curves' bases and surfaces on the unit square: plain data,
// and their evaluation with OpenCASCADE's basis functions (BSplCLib) behind this header.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/geom/parametric_surface.h"

namespace scallop {

// A B-spline surface S(u, v) = sum_ij N_i(u) M_j(v) P_ij on [0, 1]^2.
//   degree_u, degree_v  polynomial degrees (1..3 here: bicubic where the data allow)
//   knots_u, knots_v    clamped flat knot vectors (the ends repeated degree + 1 times),
//                       non-decreasing from 0 to 1, #poles + degree + 1 entries each
//   poles_u, poles_v    how many poles along u and along v
//   poles               poles_u * poles_v control points, P_ij at poles[j * poles_u + i]
//                       (row j along v, column i along u: the same layout as a patch's grid)
struct BSplineSurface {
  int degree_u = 3, degree_v = 3;
  std::vector<double> knots_u, knots_v;
  std::uint32_t poles_u = 0, poles_v = 0;
  std::vector<Eigen::Vector3d> poles;

  const Eigen::Vector3d& pole(std::uint32_t i, std::uint32_t j) const { return poles[std::size_t(j) * poles_u + i]; }
};

// The clamped knot vector of `poles` poles of degree `degree` (1 <= degree < poles) with the inner
// knots equally spaced on [0, 1].
std::vector<double> clamped_uniform_knots(int poles, int degree);

// The clamped knot vector of `poles` poles of degree `degree` (1 <= degree < poles) for
// interpolating as many points at t_k = k / (poles - 1): each inner knot the mean of `degree`
// consecutive t_k (de Boor's averaging, The NURBS Book eq. 9.8). With equally spaced inner knots
// that do not follow the points the interpolation is ill-conditioned: measured, a 91-point border
// of the ABC plate swung 273 m off its points.
std::vector<double> averaged_knots(int poles, int degree);

// The B-spline basis functions of `knots` (degree `degree`) that are non-zero at t in [0, 1],
// with derivatives up to `derivatives` (<= degree): values(d, k) is the d-th derivative of basis
// function first + k, k = 0..degree.
constexpr int kMaxDegree = 9;
struct BasisAt {
  int first = 0;
  // (derivatives + 1) by (degree + 1), held inline (no allocation per evaluation)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDegree + 1, kMaxDegree + 1> values;
};
BasisAt bspline_basis(const std::vector<double>& knots, int degree, double t, int derivatives);

// The surface and its partial derivatives at (u, v), up to the second (order 2) or the first
// (order 1: duu, duv and dvv left zero; a sample's point and normal need no more, and the planners
// ask for samples far more often than for curvatures).
struct SurfaceJet {
  Eigen::Vector3d point, du, dv, duu, duv, dvv;
};
SurfaceJet evaluate(const BSplineSurface& s, double u, double v, int order = 2);
Eigen::Vector3d surface_point(const BSplineSurface& s, double u, double v);

// A B-spline surface as the planners see it (ParametricSurface): the unit square, exact
// derivatives, the normal ru x rv turned to the side of `up` (the patch's machining direction:
// away from the material), and a constant uncertainty (mm; how far the part may lie from the
// surface, 0 when it is taken as exact). Where ru x rv vanishes (a border collapsed to a point)
// the normal is up. Holds its own copy of the surface.
//
// min_up_dot: the patch's normals are known to lie within this of up (n . up >= min_up_dot: the
// segmentation's cap, less the fit's slack). Where ru x rv falls outside it, the patch's (u, v)
// map is degenerate there (a corner of nearly 180 degrees, where ru and rv are nearly parallel,
// or the crease where a fitted surface folds over) and ru x rv points nowhere in particular (a
// ball placed along it on the domed block stood beside the part and was lifted 3 mm): the normal
// is taken from the nearest point on the way to the square's centre whose normal lies within it
// (up if none). The default, -1, takes ru x rv everywhere.
class BSplinePatch final : public ParametricSurface {
 public:
  BSplinePatch(BSplineSurface surface, const Eigen::Vector3d& up, double uncertainty = 0, double min_up_dot = -1);
  SurfaceSample operator()(const Eigen::Vector2d& uv) const override;
  SurfaceDerivatives derivatives(const Eigen::Vector2d& uv) const override;
  const UVDomain& domain() const override { return domain_; }
  // A quarter of the smaller knot span, in parameter units.
  double uv_spacing() const override { return spacing_; }
  const BSplineSurface& surface() const { return surface_; }

 private:
  // The point and normal of the jet j at uv (clamped to the square).
  SurfaceSample sample(const SurfaceJet& j, const Eigen::Vector2d& uv) const;

  BSplineSurface surface_;
  Eigen::Vector3d up_;
  double uncertainty_, min_up_dot_;
  UVDomain domain_;
  double spacing_;
  std::uint64_t id_;  // a number no other patch gets: the key of each thread's last basis evaluated
};

// Empty when s is well formed (degrees, knot counts and order, pole count, finite poles),
// otherwise what is wrong.
std::string bspline_problem(const BSplineSurface& s);

}  // namespace scallop
