// A B-spline surface per sharp height field (surface.fit_bspline).
//
// papers/point-clouds-to-workpieces.md, "Tool path planning with certified scallop height": each
// SHF is fitted by a uniform bicubic B-spline, C0 across the SHFs' borders; the paper minimises
// the fitting error plus alpha times the thin-plate energy F1 and refines until the error is under
// a threshold. Here the SHF is a rectangle of the quad grid (mesh.segment), so its own grid
// indices are the parameterisation: vertex (i, j) of a rows by cols grid sits at
// (u, v) = (j / (cols-1), i / (rows-1)), and the surface has as many poles as the grid has
// vertices along each direction (degree min(3, count - 1)), knots averaged from those parameters
// (averaged_knots: equally spaced knots made long borders swing off, 273 m on the ABC plate). Then:
//   1. each of the four borders is fitted alone, as a curve through its own vertices (ends held
//      at the corners), so two patches that share a whole border (same vertices) get the very
//      same boundary curve: C0 by construction, not by tolerance;
//   2. the inner poles minimise |S(u_k, v_k) - p_k|^2 + lambda F1, the border poles held at the
//      curves' poles;
//   3. lambda = alpha * trace(A^T A) / trace(F1) (so alpha does not depend on the grid's size or
//      the part's scale). alpha = 0 is interpolation (as many poles as points): the reference
//      between the vertices. Starting at `smoothing` and dividing by 10, the first alpha whose
//      surface lies within `tolerance` of every vertex and within 0.8 `tolerance` of the
//      interpolant at quarter steps between them (a fifth kept for what lies between) is kept (smoothing alone would meet the vertices and bulge between them, measured on
//      a sphere cap: 0.0006 mm at the vertices, 0.0048 between); none: the interpolant.
// Where two patches share only part of a border (a T-junction of the quad layout), their curves
// differ: the gap between the surfaces along every shared mesh edge is measured and reported.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "nodes/geom/bspline_surface.h"
#include "nodes/types/mesh.h"
#include "nodes/types/segments.h"
#include "nodes/types/surfaces.h"

namespace scallop {

struct FitBSplineOptions {
  double tolerance = 0.00125;  // mm: largest distance from a grid vertex to its point on the surface
  double smoothing = 1e-2;     // alpha of the first try (thin-plate weight, relative)
  int refinements = 8;         // tries with alpha / 10 each before alpha = 0
  // With the part's mesh given: the grids are made twice as fine (subdivide_segments.h), at most
  // this many times, while some surface lies farther than part_tolerance off the part.
  int subdivisions = 2;
  double part_tolerance = 0.005;  // mm
};

// A fit and how it went. error is |S(u_k, v_k) - p_k| at the vertices' own parameters: an upper
// bound of their distance to the surface.
struct GridFit {
  BSplineSurface surface;
  double max_error = 0, mean_error = 0;
  double smoothing = 0;  // the alpha that met the tolerance (0: interpolation)
  bool within_tolerance = false;
};

// A curve: points p_0 .. p_{n-1} (n >= 2) at t_k = k / (n-1), fitted with n poles of degree
// min(3, n-1), clamped uniform knots, ends at p_0 and p_{n-1}, smoothed by alpha * the integral
// of |C''|^2 and alpha chosen as above. Returns the poles; error receives the largest |C(t_k) - p_k|.
std::vector<Eigen::Vector3d> fit_border_curve(const std::vector<Eigen::Vector3d>& points, const FitBSplineOptions& options,
                                              double* error = nullptr);

// points    rows * cols grid points (rows, cols >= 2), row-major, row i along v, column j along u.
// borders   optional poles of the four border curves, each as fit_border_curve returns them for
//           the grid's border in this order: row 0 (j = 0 .. cols-1), column cols-1 (i = 0 ..
//           rows-1), row rows-1 (j = 0 .. cols-1), column 0 (i = 0 .. rows-1); empty: fitted here.
GridFit fit_grid_bspline(const std::vector<Eigen::Vector3d>& points, std::uint32_t rows, std::uint32_t cols,
                         const FitBSplineOptions& options, const std::vector<std::vector<Eigen::Vector3d>>& borders = {});

// The largest distance from each patch's surface, sampled at quarter steps of its grid (rows by
// cols), to `mesh`'s faces (+infinity when it has none): against the quads it was fitted to, its
// mesh_distance_max; against the part's own mesh, how far the surface the paths follow may lie
// off the part (path.contour_grid).
std::vector<double> surface_distance_max(const Surfaces& surfaces, const Mesh& mesh);

// The same distances kept where they were sampled: per patch a (nu + 1) by (nv + 1) grid at
// (u, v) = (j / nu, i / nv), row-major (row i along u), nu = 4 (cols - 1), nv = 4 (rows - 1).
struct SurfaceDistanceGrid {
  std::uint32_t nu = 0, nv = 0;
  std::vector<double> distance;
  // The largest distance at the samples within one sample step of the (u, v) box [u0, u1] x [v0,
  // v1] (0 for an empty grid).
  double max_near(double u0, double u1, double v0, double v1) const;
};
std::vector<SurfaceDistanceGrid> surface_distance_grids(const Surfaces& surfaces, const Mesh& mesh);

// A fitted patch as the planners see it: up its machining direction, and its normals held within
// its segment's cap (n . direction >= min_normal_dot) less 0.1, the fit's own lean (BSplinePatch:
// where the fitted map degenerates, the normal is taken from inside).
BSplinePatch machining_surface(const SurfacePatch& patch);

// How the patches meet, and how close they came to the part.
struct FitStats {
  int subdivisions = 0;                 // times the grids were made twice as fine
  double part_distance_before = 0;      // mm, the farthest surface from the part before (0: no part)
  double part_distance_after = 0;       // and after
  std::vector<double> part_distance;    // per patch, after
  std::size_t shared_borders = 0;   // whole borders two patches share (one curve)
  std::size_t shared_edges = 0;     // mesh edges on the border of two patches
  double boundary_gap_max = 0;      // largest distance between two patches' surfaces along those edges
  std::size_t boundary_gap_patch_a = 0, boundary_gap_patch_b = 0;  // where (patch indices)
};

// Every patch of `segments` fitted, borders shared. With `part` (the mesh the quads were made
// from, its feature_edges set), the grids are subdivided and fitted again while some patch lies
// farther than options.part_tolerance off the part (surface_distance_max), at most
// options.subdivisions times; the patches' rows and cols are then the finer grids'. Throws
// std::invalid_argument naming the patch when its grid has a non-finite vertex.
Surfaces fit_surfaces(const Segments& segments, const FitBSplineOptions& options, FitStats* stats = nullptr,
                      const std::function<void(double, const std::string&)>& progress = {},
                      const Mesh* part = nullptr);

}  // namespace scallop
