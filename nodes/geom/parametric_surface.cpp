#include "nodes/geom/parametric_surface.h"

#include <algorithm>

namespace scallop {

Eigen::Vector2d UVDomain::clamp(const Eigen::Vector2d& uv) const {
  if (kind == Kind::Rectangle) return {std::clamp(uv.x(), 0.0, width), std::clamp(uv.y(), 0.0, height)};
  const double n = uv.norm();
  return n > radius ? Eigen::Vector2d(uv * (radius / n)) : uv;
}

SurfaceDerivatives ParametricSurface::derivatives(const Eigen::Vector2d& uv) const {
  const double h = 2 * uv_spacing();
  Eigen::Vector2d c = uv;
  const UVDomain& d = domain();
  if (d.kind == UVDomain::Kind::Rectangle) {
    c.x() = std::clamp(uv.x(), std::min(h, 0.5 * d.width), std::max(d.width - h, 0.5 * d.width));
    c.y() = std::clamp(uv.y(), std::min(h, 0.5 * d.height), std::max(d.height - h, 0.5 * d.height));
  }
  auto P = [&](double du, double dv) { return (*this)(c + Eigen::Vector2d(du, dv)).position; };
  SurfaceDerivatives r;
  r.sample = (*this)(uv);
  // (the stencil's centre is the sample itself unless it was moved inside)
  const Eigen::Vector3d p0 = c == uv ? r.sample.position : P(0, 0), pu = P(h, 0), mu = P(-h, 0), pv = P(0, h),
                        mv = P(0, -h);
  r.ru = (pu - mu) / (2 * h);
  r.rv = (pv - mv) / (2 * h);
  r.ruu = (pu + mu - 2 * p0) / (h * h);
  r.rvv = (pv + mv - 2 * p0) / (h * h);
  r.ruv = (P(h, h) - P(h, -h) - P(-h, h) + P(-h, -h)) / (4 * h * h);
  return r;
}

}  // namespace scallop
