// What a tool-path planner asks of a surface: its parameter domain and, at (u, v), the point, the
// unit normal (pointing away from the material), how uncertain the point is, and the first and
// second derivatives. Two surfaces answer: the first paper's interpolant over a parameterised
// cloud (UVInterpolator, nodes/path/uv_interpolation.h) and a B-spline patch of the second paper
// (BSplinePatch, nodes/geom/bspline_surface.h), so a planner written against this works on both.
#pragma once

#include <Eigen/Core>

namespace scallop {

// The parameter domain: [0, width] x [0, height], or the disk of `radius` centred at the origin.
struct UVDomain {
  enum class Kind { Rectangle, Disk };
  Kind kind = Kind::Rectangle;
  double width = 0, height = 0;  // Rectangle
  double radius = 0;             // Disk

  // The nearest point of the domain (the point itself when inside).
  Eigen::Vector2d clamp(const Eigen::Vector2d& uv) const;
};

struct SurfaceSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   // unit
  double uncertainty = 0;    // mm: how far the real surface may lie from position (0: exact)
};

// r(u, v) and its partial derivatives (mm per parameter unit), with the sample's normal and
// uncertainty.
struct SurfaceDerivatives {
  SurfaceSample sample;
  Eigen::Vector3d ru, rv, ruu, ruv, rvv;
};

class ParametricSurface {
 public:
  virtual ~ParametricSurface() = default;
  // Position, unit normal and uncertainty at uv; a uv outside the domain is first clamped onto
  // it. Const and thread-safe.
  virtual SurfaceSample operator()(const Eigen::Vector2d& uv) const = 0;
  virtual const UVDomain& domain() const = 0;
  // The scale of the surface's detail in uv (the data's sampling step): finite differences are
  // taken at about this step.
  virtual double uv_spacing() const = 0;
  // The derivatives at uv. By default central differences of step 2 uv_spacing() through
  // operator(), the stencil moved inside a rectangle's domain where uv lies on its edge; a
  // surface that knows them exactly overrides this.
  virtual SurfaceDerivatives derivatives(const Eigen::Vector2d& uv) const;
};

}  // namespace scallop
