// Values of the parameterisation steps: boundary loops, the meshless Laplacian, the (u,v) map.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// Boundary points of an open patch, ordered into closed loops. loops[0] is the outer loop, the
// rest are holes; each loop lists point indices in order (no repeated first index at the end).
// is_boundary[i] != 0 for every boundary point, including points not placed on any loop.
struct BoundaryLoops final : Value {
  std::vector<std::vector<int>> loops;
  std::vector<std::uint8_t> is_boundary;  // #P

  std::string type_name() const override { return "Loops"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

// The loops as closed polygons of their points' (x, y) (the patch's outline seen from +z).
// Throws std::invalid_argument when there is no loop or a loop refers to a point `points` lacks.
std::vector<std::vector<Eigen::Vector2d>> loop_polygons_xy(const BoundaryLoops& loops,
                                                           const std::vector<Eigen::Vector3d>& points);

// A meshless Laplacian: L is #P by #P, row i is the operator at point i
// ((L f)_i = sum_j w_ij (f_i - f_j), rows sum to zero).
struct Laplacian final : Value {
  std::string scheme;  // "uniform", "heat", "optimal"
  double heat_time = 0;       // mm^2, the heat scheme's t
  double regularization = 0;  // the optimal scheme's delta
  Eigen::SparseMatrix<double, Eigen::RowMajor> L;

  std::string type_name() const override { return "Laplacian"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

// A parameterisation of the cloud: uv[i] is the parameter-domain position of point i.
// domain "disk": the outer loop maps to the circle of radius `radius` centred at the origin
// (contour-parallel paths); domain "rectangle": to [0,width] x [0,height] (direction-parallel);
// domain "planar" (param.planar): uv is the points' xy turned, over [0,width] x [0,height], and the
// outer loop lies inside that rectangle: off it is off the patch (direction-parallel, a raster).
// boundary_uv holds the fixed positions of the outer loop's points, in loop order.
struct UVMap final : Value {
  std::string domain;  // "disk", "rectangle" or "planar"
  double radius = 0;
  double width = 0, height = 0;
  std::vector<Eigen::Vector2d> uv;         // #P
  std::vector<int> outer_loop;             // point indices of the outer loop, in order
  std::vector<Eigen::Vector2d> boundary_uv;  // #outer_loop
  std::vector<int> corners;                // rectangle: positions in outer_loop of the 4 corners
  double residual = 0;                     // relative residual of the harmonic solve

  std::string type_name() const override { return "UVMap"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

}  // namespace scallop
