// Surfaces value: one B-spline surface per sharp height field of a part (surface.fit_bspline), the
// second method's patches ready for contour paths and for CAD (io.write_step).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/value.h"
#include "nodes/geom/bspline_surface.h"

namespace scallop {

// One patch.
//   surface         S(u, v) on the domain [0, 1]^2; S_u x S_v points toward the spindle
//                   (along direction), as the patch's faces do
//   direction       unit machining direction (tool axis, surface to spindle), min_normal_dot the
//                   smallest n . direction over the patch's mesh faces (mesh.segment's figures;
//                   -1 where not known)
//   segment         the patch's index in the Segments it was fitted from
//   rows, cols      the grid fitted (vertex (i, j) at (u, v) = (j / (cols-1), i / (rows-1)))
//   fit_max_error, fit_mean_error   |S(u, v) - vertex| over that grid (mm)
//   smoothing       the thin-plate weight alpha the fit ended with (0: interpolation)
//   mesh_distance_max  the largest distance from the surface (sampled at quarter steps of its
//                   grid) to the mesh it was fitted to: the facets' sag where the part is curved,
//                   and any bulge of the fit between the vertices
struct SurfacePatch {
  BSplineSurface surface;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double min_normal_dot = -1;
  std::uint32_t segment = 0;
  std::uint32_t rows = 0, cols = 0;
  double fit_max_error = 0, fit_mean_error = 0, smoothing = 0;
  double mesh_distance_max = 0;
};

// patches         the fitted patches
// tolerance       the fit's tolerance (mm)
// base_direction  unit outward normal of the clamping base, or zero (as in Segments)
struct Surfaces final : Value {
  std::vector<SurfacePatch> patches;
  double tolerance = 0;
  Eigen::Vector3d base_direction = Eigen::Vector3d::Zero();

  std::string type_name() const override { return "Surfaces"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // Writes JSON: per patch its direction, figures, degrees, knots and poles.
  void write_file(const std::string& path) const override;
};

}  // namespace scallop
