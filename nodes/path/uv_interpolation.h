// Positions and normals of a parameterised cloud at arbitrary (u, v), with linear precision.
//
// The paper (section 3.3) writes a point at (u, v) as an affine combination of the points whose
// uv images are its nearest neighbours, with weights that reproduce linear functions (linear
// precision). We use a weighted local quadratic least-squares fit of x, y, z (and of the
// normal) against (u, v) over the k nearest uv neighbours: it reproduces linear and quadratic
// functions exactly, so curvatures taken from it by finite differences are exact on quadrics
// (the paper's scheme is exact only on planes). Each weight (1 - d^2/D^2)^2 vanishes at D, the
// distance to the (k+1)-th neighbour, so the interpolant is continuous in (u, v) even where the
// neighbour set changes. The normal returned is that of the fitted position surface (the cross
// product of its u and v tangents), oriented like the point normals; the fitted point normals
// are blended in near the domain's edge (where the fit extrapolates) and used where that fit is
// degenerate or disagrees with them by more than 10 degrees.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "nodes/geom/parametric_surface.h"

namespace scallop {

class UVInterpolator final : public ParametricSurface {
 public:
  // P   #P by 3 positions (mm)
  // N   #P by 3 unit normals (oriented consistently, e.g. up)
  // UV  #P by 2 parameter positions, inside `domain`
  // k   neighbours per fit, 6 <= k < #P (20 is a good default)
  // uncertainty  optional #P per-point bounds (mm, PointCloud::uncertainty); their weighted
  //              power mean of order 8 over the points of a fit (continuous, near their
  //              largest value: a certificate that averages them over other neighbours, as
  //              post.simulate does, stays below it) goes into SurfaceSample::uncertainty
  // Keeps references to P, N, UV and uncertainty: they must outlive the interpolator and not
  // change.
  // Throws std::invalid_argument for mismatched sizes, too few points, a bad k or a non-finite
  // coordinate.
  UVInterpolator(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                 const std::vector<Eigen::Vector2d>& UV, UVDomain domain, int k = 20,
                 const std::vector<double>* uncertainty = nullptr);
  ~UVInterpolator();
  UVInterpolator(const UVInterpolator&) = delete;
  UVInterpolator& operator=(const UVInterpolator&) = delete;

  // Position and unit normal at uv; a uv outside the domain is first clamped onto it.
  // Const and thread-safe.
  SurfaceSample operator()(const Eigen::Vector2d& uv) const override;

  const UVDomain& domain() const override { return domain_; }
  // Median distance, in uv, from a point to its nearest other point: the sampling scale of the
  // map (finite-difference steps are taken from it).
  double uv_spacing() const override { return uv_spacing_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  UVDomain domain_;
  double uv_spacing_ = 0;
};

}  // namespace scallop
