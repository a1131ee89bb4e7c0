// A local surface of a few points: their least-squares plane and a quadric height over it. Shared
// by mesh.sharpen (each region's surface near an edge, where two meet) and mesh.cloud_envelope
// (the points' surface beside a vertex the mesh extrapolated).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

namespace scallop {

// A surface near a point: a quadric height w(u, v) over the least-squares plane of the points
// there (frame t1, t2, normal about point), or that plane where a quadric is not
// determined (too few points, or all on a line).
struct LocalSurface {
  Eigen::Vector3d normal, point, t1, t2;
  std::array<double, 6> c{};  // w = c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2, (u, v) in mm
  // Height of x above the surface (along normal), and its gradient.
  double value(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = x - point;
    const double u = d.dot(t1), v = d.dot(t2);
    return d.dot(normal) - (c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v);
  }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = x - point;
    const double u = d.dot(t1), v = d.dot(t2);
    return normal - (c[1] + 2 * c[3] * u + c[4] * v) * t1 - (c[2] + c[4] * u + 2 * c[5] * v) * t2;
  }
  double distance(const Eigen::Vector3d& x) const { return std::abs(value(x)) / gradient(x).norm(); }
};

// The local surface of the points: their plane, then a quadric over it where they determine one.
// Fewer than kMinSurfacePoints points are a sliver of a region, not its surface (on a sphere cut
// into regions, a plane through 5 points of one stood 70 degrees off the sphere).
constexpr std::size_t kMinSurfacePoints = 10;
std::optional<LocalSurface> fit_local_surface(const std::vector<Eigen::Vector3d>& pts);

}  // namespace scallop
