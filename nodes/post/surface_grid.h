// The certificate's surface samples: the cloud's height field on a square xy grid rotated by
// 0.3 rad, spacing sqrt(8 r h) / 12 (verify.py's grid, ../shared/tools/README), over the patch
// the outline bounds (and the rim band beyond it when asked). post.simulate traces the path's
// balls at them; they need only the cloud, the outline and the limits, so post.surface_samples
// takes them while the path is planned.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <functional>

#include "nodes/geom/height_field_model.h"
#include "nodes/types/surface_samples.h"

namespace scallop {

constexpr double kGridAngle = 0.3;                     // rad, as verify.py ...
constexpr double kGridPhaseU = 0.37, kGridPhaseV = 0.71;  // ... and its shift, in spacings

// Where the grid's nodes are: node (i, j) at grid coordinates (u(i), v(j)), turned by kGridAngle
// about (cx, cy) into xy.
struct GridFrame {
  double spacing, cx, cy, extent;
  int nodes;
  double ca = std::cos(kGridAngle), sa = std::sin(kGridAngle);
  double u(int i) const { return -extent + (i + kGridPhaseU) * spacing; }
  double v(int j) const { return -extent + (j + kGridPhaseV) * spacing; }
  Eigen::Vector2d xy(double gu, double gv) const { return {cx + ca * gu - sa * gv, cy + sa * gu + ca * gv}; }
  // The index (j nu + i) of the node nearest (x, y); -1 off the grid.
  std::ptrdiff_t nearest(double x, double y) const {
    const double dx = x - cx, dy = y - cy, gu = ca * dx + sa * dy, gv = -sa * dx + ca * dy;
    const long i = std::lround((gu + extent) / spacing - kGridPhaseU), j = std::lround((gv + extent) / spacing - kGridPhaseV);
    return i >= 0 && j >= 0 && i < nodes && j < nodes ? std::ptrdiff_t(j) * nodes + i : -1;
  }
};
inline GridFrame grid_frame(const SurfaceSamples& s) { return {s.spacing, s.cx, s.cy, s.extent, s.nodes}; }

// Samples `surface` on the grid `options` describe (SurfaceGridOptions): which nodes are on the
// patch (inside the outer loop and outside the holes; without loops, where the cloud is, its
// holes counted in), each on-patch node's place, normal, area and uncertainty (steep cells split
// k × k, k = round(1 / n_z) up to 4, so the spacing along the surface stays near the grid's),
// and the rim band's nodes off the patch, beyond the outer loop or in a hole (within rim_band ×
// n_z of the nearest loop; rim_band < 0: one cloud spacing). progress, when given, is called with fractions in [0, 1].
// Throws std::invalid_argument for r <= 0, h <= 0, an outer loop of fewer than 3 points, a
// non-finite loop point, or no sample on the surface.
SurfaceSamples sample_surface_grid(const HeightFieldModel& surface, const SurfaceGridOptions& options,
                                   const std::function<void(double)>& progress = {});

}  // namespace scallop
