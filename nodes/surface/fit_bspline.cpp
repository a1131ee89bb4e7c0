#include "nodes/surface/fit_bspline.h"

#include <Eigen/Cholesky>
#include <Eigen/Sparse>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/surface/subdivide_segments.h"

namespace scallop {

namespace {

// One direction of n data points at t_k = k / (n-1) and n poles: B(k, i) = N_i(t_k), Fine the same
// at kFine times as many parameters t = k / (kFine (n-1)) (the points and between them), and the
// Gram matrices Gd(i, l) = integral over [0, 1] of N_i^(d) N_l^(d), d = 0, 1, 2.
constexpr int kFine = 4;
// Between the quarter steps the smoothed surface may stray a little further from the interpolant
// than at them: a fifth of the tolerance is kept for that.
constexpr double kBetween = 0.8;
struct Basis1D {
  int degree = 1;
  std::vector<double> knots;
  Eigen::MatrixXd B, Fine, G0, G1, G2;
};

Basis1D basis_1d(int n) {
  Basis1D b;
  b.degree = std::min(3, n - 1);
  b.knots = averaged_knots(n, b.degree);
  b.B = Eigen::MatrixXd::Zero(n, n);
  b.Fine = Eigen::MatrixXd::Zero(kFine * (n - 1) + 1, n);
  for (int k = 0; k < b.Fine.rows(); ++k) {
    const BasisAt a = bspline_basis(b.knots, b.degree, double(k) / (kFine * (n - 1)), 0);
    for (int c = 0; c <= b.degree; ++c) {
      b.Fine(k, a.first + c) = a.values(0, c);
      if (k % kFine == 0) b.B(k / kFine, a.first + c) = a.values(0, c);
    }
  }
  b.G0 = b.G1 = b.G2 = Eigen::MatrixXd::Zero(n, n);
  // Gauss-Legendre with 4 points per knot span: exact for the products (degree <= 6).
  static constexpr double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  static constexpr double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  const int d = std::min(2, b.degree);
  for (std::size_t s = 0; s + 1 < b.knots.size(); ++s) {
    const double lo = b.knots[s], hi = b.knots[s + 1];
    if (hi <= lo) continue;
    for (int q = 0; q < 4; ++q) {
      const double t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x[q], wt = 0.5 * (hi - lo) * w[q];
      const BasisAt a = bspline_basis(b.knots, b.degree, t, d);
      for (int c = 0; c <= b.degree; ++c)
        for (int e = 0; e <= b.degree; ++e) {
          const int i = a.first + c, l = a.first + e;
          b.G0(i, l) += wt * a.values(0, c) * a.values(0, e);
          b.G1(i, l) += wt * a.values(1, c) * a.values(1, e);
          if (d >= 2) b.G2(i, l) += wt * a.values(2, c) * a.values(2, e);
        }
    }
  }
  return b;
}

// The weights alpha is tried with before interpolation (alpha = 0): smoothing, / 10, ...
std::vector<double> smoothing_steps(const FitBSplineOptions& o) {
  std::vector<double> alphas;
  for (int k = 0; o.smoothing > 0 && k <= o.refinements; ++k) alphas.push_back(o.smoothing * std::pow(10.0, -k));
  return alphas;
}

// Adds scale * kron(outer, inner) to `t`: entry ((i, k), (j, l)) at (i * inner.rows() + k, j * inner.cols() + l).
void add_kron(std::vector<Eigen::Triplet<double>>& t, const Eigen::MatrixXd& outer, const Eigen::MatrixXd& inner,
              double scale) {
  for (int i = 0; i < outer.rows(); ++i)
    for (int j = 0; j < outer.cols(); ++j) {
      if (outer(i, j) == 0) continue;
      for (int k = 0; k < inner.rows(); ++k)
        for (int l = 0; l < inner.cols(); ++l)
          if (inner(k, l) != 0)
            t.emplace_back(int(i * inner.rows() + k), int(j * inner.cols() + l), scale * outer(i, j) * inner(k, l));
    }
}

// The four borders of a rows by cols grid, as fit_grid_bspline takes them: row 0, column cols-1,
// row rows-1 (along j), column 0 (along i); at(i, j) gives the grid's element.
template <class At>
auto grid_borders(std::uint32_t rows, std::uint32_t cols, At at) {
  std::array<std::vector<std::decay_t<decltype(at(0u, 0u))>>, 4> side;
  for (std::uint32_t j = 0; j < cols; ++j) side[0].push_back(at(0, j)), side[2].push_back(at(rows - 1, j));
  for (std::uint32_t i = 0; i < rows; ++i) side[1].push_back(at(i, cols - 1)), side[3].push_back(at(i, 0));
  return side;
}

}  // namespace

std::vector<Eigen::Vector3d> fit_border_curve(const std::vector<Eigen::Vector3d>& points, const FitBSplineOptions& o,
                                              double* error) {
  const int n = static_cast<int>(points.size());
  if (n < 2) throw std::invalid_argument("fit_border_curve: a curve needs 2 points or more");
  if (error) *error = 0;
  if (n == 2) return points;  // degree 1: the poles are the points
  const Basis1D b = basis_1d(n);
  Eigen::MatrixXd X(n, 3);
  for (int k = 0; k < n; ++k) X.row(k) = points[k].transpose();
  const Eigen::MatrixXd M = b.B.transpose() * b.B;
  const Eigen::MatrixXd R = b.B.transpose() * X;
  const double scale = b.G2.trace() > 0 ? M.trace() / b.G2.trace() : 0;
  // The ends are held at the end points (a clamped curve passes through its end poles).
  const int m = n - 2;
  auto solve = [&](double alpha) {
    const Eigen::MatrixXd K = M + alpha * scale * b.G2;
    const Eigen::MatrixXd rhs =
        R.middleRows(1, m) - K.block(1, 0, m, 1) * X.row(0) - K.block(1, n - 1, m, 1) * X.row(n - 1);
    Eigen::MatrixXd P = X;
    P.middleRows(1, m) = K.block(1, 1, m, m).ldlt().solve(rhs);
    return P;
  };
  // The interpolant is the reference between the points: a smoother curve is taken only where it
  // stays within the tolerance of the points and of the interpolant between them (quarter steps).
  Eigen::MatrixXd P = solve(0);
  const Eigen::MatrixXd reference = b.Fine * P;
  double err = (b.B * P - X).rowwise().norm().maxCoeff();
  for (double alpha : smoothing_steps(o)) {
    const Eigen::MatrixXd Pa = solve(alpha);
    const double e = (b.B * Pa - X).rowwise().norm().maxCoeff();
    if (e <= o.tolerance && (b.Fine * Pa - reference).rowwise().norm().maxCoeff() <= kBetween * o.tolerance) {
      P = Pa, err = e;
      break;
    }
  }
  if (error) *error = err;
  std::vector<Eigen::Vector3d> poles(n);
  for (int k = 0; k < n; ++k) poles[k] = P.row(k).transpose();
  return poles;
}

GridFit fit_grid_bspline(const std::vector<Eigen::Vector3d>& points, std::uint32_t rows, std::uint32_t cols,
                         const FitBSplineOptions& o, const std::vector<std::vector<Eigen::Vector3d>>& given_borders) {
  if (rows < 2 || cols < 2 || points.size() != std::size_t(rows) * cols)
    throw std::invalid_argument("fit_grid_bspline: " + std::to_string(points.size()) + " points for a " +
                                std::to_string(rows) + " by " + std::to_string(cols) + " grid (2 by 2 at least)");
  const int nu = int(cols), nv = int(rows);
  auto at = [&](int i, int j) -> const Eigen::Vector3d& { return points[std::size_t(i) * cols + j]; };
  std::vector<std::vector<Eigen::Vector3d>> borders = given_borders;
  if (borders.empty())
    for (const auto& side : grid_borders(rows, cols, at)) borders.push_back(fit_border_curve(side, o));
  if (borders.size() != 4 || int(borders[0].size()) != nu || int(borders[2].size()) != nu ||
      int(borders[1].size()) != nv || int(borders[3].size()) != nv)
    throw std::invalid_argument("fit_grid_bspline: border curves do not match the grid");

  const Basis1D bu = basis_1d(nu), bv = basis_1d(nv);
  GridFit fit;
  BSplineSurface& s = fit.surface;
  s.degree_u = bu.degree, s.degree_v = bv.degree;
  s.knots_u = bu.knots, s.knots_v = bv.knots;
  s.poles_u = cols, s.poles_v = rows;
  s.poles.assign(points.size(), Eigen::Vector3d::Zero());
  auto pole = [&](int a, int b) -> Eigen::Vector3d& { return s.poles[std::size_t(b) * nu + a]; };
  for (int a = 0; a < nu; ++a) pole(a, 0) = borders[0][a], pole(a, nv - 1) = borders[2][a];
  for (int b = 0; b < nv; ++b) pole(nu - 1, b) = borders[1][b], pole(0, b) = borders[3][b];

  // Poles and points are indexed a + nu * b (u fastest), so A = kron(Bv, Bu).
  std::vector<int> inner(std::size_t(nu) * nv, -1);
  int unknowns = 0;
  for (int b = 1; b + 1 < nv; ++b)
    for (int a = 1; a + 1 < nu; ++a) inner[std::size_t(b) * nu + a] = unknowns++;

  std::vector<Eigen::MatrixXd> X(3, Eigen::MatrixXd(nu, nv));
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < nv; ++b)
      for (int a = 0; a < nu; ++a) X[c](a, b) = at(b, a)[c];
  auto measure = [&] {
    Eigen::ArrayXXd err2 = Eigen::ArrayXXd::Zero(nu, nv);
    for (int c = 0; c < 3; ++c) {
      Eigen::MatrixXd P(nu, nv);
      for (int b = 0; b < nv; ++b)
        for (int a = 0; a < nu; ++a) P(a, b) = pole(a, b)[c];
      err2 += (bu.B * P * bv.B.transpose() - X[c]).array().square();
    }
    const Eigen::ArrayXXd err = err2.sqrt();
    fit.max_error = err.maxCoeff();
    fit.mean_error = err.mean();
  };

  // The surface at the vertices and at quarter steps between them, per coordinate.
  auto on_fine_grid = [&](const std::vector<Eigen::Vector3d>& poles) {
    std::array<Eigen::MatrixXd, 3> out;
    for (int c = 0; c < 3; ++c) {
      Eigen::MatrixXd P(nu, nv);
      for (int b = 0; b < nv; ++b)
        for (int a = 0; a < nu; ++a) P(a, b) = poles[std::size_t(b) * nu + a][c];
      out[c] = bu.Fine * P * bv.Fine.transpose();
    }
    return out;
  };
  if (unknowns > 0) {
    std::vector<Eigen::Triplet<double>> tm, tf;
    add_kron(tm, bv.B.transpose() * bv.B, bu.B.transpose() * bu.B, 1.0);
    add_kron(tf, bv.G0, bu.G2, 1.0);
    add_kron(tf, bv.G1, bu.G1, 2.0);
    add_kron(tf, bv.G2, bu.G0, 1.0);
    const int n = nu * nv;
    Eigen::SparseMatrix<double> M(n, n), F(n, n);
    M.setFromTriplets(tm.begin(), tm.end());
    F.setFromTriplets(tf.begin(), tf.end());
    double trace_m = 0, trace_f = 0;
    for (int k = 0; k < n; ++k) trace_m += M.coeff(k, k), trace_f += F.coeff(k, k);
    const double scale = trace_f > 0 ? trace_m / trace_f : 0;
    // A^T x per coordinate: Bu^T X Bv.
    Eigen::MatrixXd R(n, 3);
    for (int c = 0; c < 3; ++c) {
      const Eigen::MatrixXd r = bu.B.transpose() * X[c] * bv.B;
      for (int b = 0; b < nv; ++b)
        for (int a = 0; a < nu; ++a) R(b * nu + a, c) = r(a, b);
    }
    auto solve = [&](double alpha) {
      const Eigen::SparseMatrix<double> K = M + (alpha * scale) * F;
      std::vector<Eigen::Triplet<double>> tk;
      Eigen::MatrixXd rhs(unknowns, 3);
      for (int k = 0; k < n; ++k)
        if (inner[k] >= 0) rhs.row(inner[k]) = R.row(k);
      for (int col = 0; col < K.outerSize(); ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it) {
          const int r = inner[it.row()], q = inner[it.col()];
          if (r < 0) continue;
          if (q >= 0)
            tk.emplace_back(r, q, it.value());
          else  // a border pole, held: its part moves to the right-hand side
            rhs.row(r) -= it.value() * s.poles[it.col()].transpose();
        }
      Eigen::SparseMatrix<double> KI(unknowns, unknowns);
      KI.setFromTriplets(tk.begin(), tk.end());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(KI);
      if (solver.info() != Eigen::Success) throw std::runtime_error("fit_grid_bspline: the fit's system is singular");
      const Eigen::MatrixXd P = solver.solve(rhs);
      std::vector<Eigen::Vector3d> poles = s.poles;
      for (int k = 0; k < n; ++k)
        if (inner[k] >= 0) poles[k] = P.row(inner[k]).transpose();
      return poles;
    };
    // As for the curves: the interpolant is the reference between the vertices.
    s.poles = solve(0);
    const std::array<Eigen::MatrixXd, 3> reference = on_fine_grid(s.poles);
    const std::vector<Eigen::Vector3d> interpolant = s.poles;
    for (double alpha : smoothing_steps(o)) {
      s.poles = solve(alpha);
      const std::array<Eigen::MatrixXd, 3> fine = on_fine_grid(s.poles);
      Eigen::ArrayXXd d2 = Eigen::ArrayXXd::Zero(fine[0].rows(), fine[0].cols());
      for (int c = 0; c < 3; ++c) d2 += (fine[c] - reference[c]).array().square();
      measure();
      fit.smoothing = alpha;
      if (fit.max_error <= o.tolerance && std::sqrt(d2.maxCoeff()) <= kBetween * o.tolerance) break;
      s.poles = interpolant;
      fit.smoothing = 0;
    }
    measure();
  } else {
    measure();
  }
  fit.within_tolerance = fit.max_error <= o.tolerance;
  return fit;
}

std::vector<SurfaceDistanceGrid> surface_distance_grids(const Surfaces& surfaces, const Mesh& mesh) {
  const std::size_t np = surfaces.patches.size();
  std::vector<SurfaceDistanceGrid> grids(np);
  std::vector<Eigen::Vector3d> samples;
  std::vector<std::size_t> first(np + 1, 0);
  for (std::size_t p = 0; p < np; ++p) {
    const SurfacePatch& sp = surfaces.patches[p];
    const std::uint32_t nu = kFine * (std::max<std::uint32_t>(sp.cols, 2) - 1),
                        nv = kFine * (std::max<std::uint32_t>(sp.rows, 2) - 1);
    grids[p].nu = nu, grids[p].nv = nv;
    for (std::uint32_t i = 0; i <= nv; ++i)
      for (std::uint32_t j = 0; j <= nu; ++j) samples.push_back(surface_point(sp.surface, double(j) / nu, double(i) / nv));
    first[p + 1] = samples.size();
  }
  const std::vector<double> distance = distances_to_mesh(samples, mesh);
  for (std::size_t p = 0; p < np; ++p)
    grids[p].distance.assign(distance.begin() + std::ptrdiff_t(first[p]), distance.begin() + std::ptrdiff_t(first[p + 1]));
  return grids;
}

double SurfaceDistanceGrid::max_near(double u0, double u1, double v0, double v1) const {
  if (distance.empty()) return 0;
  // Sample indices j with j / nu within 1 / nu of [u0, u1]: floor(u0 nu) - 1 .. ceil(u1 nu) + 1, clamped.
  auto range = [](double lo, double hi, std::uint32_t n) {
    const double a = std::floor(std::min(lo, hi) * n) - 1, b = std::ceil(std::max(lo, hi) * n) + 1;
    return std::pair<std::uint32_t, std::uint32_t>(std::uint32_t(std::clamp(a, 0.0, double(n))),
                                                   std::uint32_t(std::clamp(b, 0.0, double(n))));
  };
  const auto [j0, j1] = range(u0, u1, nu);
  const auto [i0, i1] = range(v0, v1, nv);
  double worst = 0;
  for (std::uint32_t i = i0; i <= i1; ++i)
    for (std::uint32_t j = j0; j <= j1; ++j) worst = std::max(worst, distance[std::size_t(i) * (nu + 1) + j]);
  return worst;
}

std::vector<double> surface_distance_max(const Surfaces& surfaces, const Mesh& mesh) {
  std::vector<double> out;
  for (const SurfaceDistanceGrid& g : surface_distance_grids(surfaces, mesh))
    out.push_back(g.distance.empty() ? 0.0 : *std::max_element(g.distance.begin(), g.distance.end()));
  return out;
}

BSplinePatch machining_surface(const SurfacePatch& patch) {
  constexpr double kFitNormalSlack = 0.1;
  return BSplinePatch(patch.surface, patch.direction, 0, patch.min_normal_dot - kFitNormalSlack);
}

namespace {

Surfaces fit_patches(const Segments& seg, const FitBSplineOptions& o, FitStats* stats,
                     const std::function<void(double, const std::string&)>& progress) {
  const Mesh& mesh = seg.mesh;
  const std::size_t np = seg.patches.size();
  // Each patch's four borders as vertex chains (fit_grid_bspline's order), each stored once under
  // its canonical direction (smaller end vertex first) so that neighbours fit the same curve.
  using Chain = std::vector<std::uint32_t>;
  std::map<Chain, std::size_t> chain_index;
  std::vector<Chain> chains;
  std::vector<std::size_t> uses;
  std::vector<std::array<std::pair<std::size_t, bool>, 4>> patch_borders(np);  // chain, reversed
  for (std::size_t p = 0; p < np; ++p) {
    const SegmentPatch& sp = seg.patches[p];
    for (auto v : sp.grid)
      if (!mesh.vertices[v].allFinite())
        throw std::invalid_argument("patch " + std::to_string(p) + ": vertex " + std::to_string(v) + " is not finite");
    const auto side = grid_borders(sp.rows, sp.cols, [&](std::uint32_t i, std::uint32_t j) { return sp.at(i, j); });
    for (int k = 0; k < 4; ++k) {
      Chain c = side[k];
      Chain r(c.rbegin(), c.rend());
      const bool reversed = r < c;
      const Chain& key = reversed ? r : c;
      auto [it, added] = chain_index.try_emplace(key, chains.size());
      if (added) chains.push_back(key), uses.push_back(0);
      ++uses[it->second];
      patch_borders[p][k] = {it->second, reversed};
    }
  }
  std::vector<std::vector<Eigen::Vector3d>> curves(chains.size());
  tbb::parallel_for(std::size_t(0), chains.size(), [&](std::size_t c) {
    std::vector<Eigen::Vector3d> pts;
    for (auto v : chains[c]) pts.push_back(mesh.vertices[v]);
    curves[c] = fit_border_curve(pts, o);
  });

  Surfaces out;
  out.tolerance = o.tolerance;
  out.base_direction = seg.base_direction;
  out.patches.resize(np);
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t(0), np, [&](std::size_t p) {
    const SegmentPatch& sp = seg.patches[p];
    std::vector<Eigen::Vector3d> pts;
    for (auto v : sp.grid) pts.push_back(mesh.vertices[v]);
    std::vector<std::vector<Eigen::Vector3d>> borders;
    for (const auto& [c, reversed] : patch_borders[p]) {
      borders.push_back(curves[c]);
      if (reversed) std::reverse(borders.back().begin(), borders.back().end());
    }
    const GridFit fit = fit_grid_bspline(pts, sp.rows, sp.cols, o, borders);
    SurfacePatch& out_p = out.patches[p];
    out_p.surface = fit.surface;
    out_p.direction = sp.direction;
    out_p.min_normal_dot = sp.min_normal_dot;
    out_p.segment = static_cast<std::uint32_t>(p);
    out_p.rows = sp.rows, out_p.cols = sp.cols;
    out_p.fit_max_error = fit.max_error, out_p.fit_mean_error = fit.mean_error;
    out_p.smoothing = fit.smoothing;
    if (progress) progress(double(++done) / double(np), "fitting B-spline patches");
  });

  const std::vector<double> distance = surface_distance_max(out, mesh);
  for (std::size_t p = 0; p < np; ++p) out.patches[p].mesh_distance_max = distance[p];

  if (stats) {
    *stats = FitStats{};
    for (auto u : uses) stats->shared_borders += u >= 2;
    // Every mesh edge on a patch border: the patches it bounds and its ends' (u, v) there, the
    // smaller vertex first.
    struct Side {
      std::size_t patch;
      Eigen::Vector2d a, b;
    };
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<Side>> edges;
    for (std::size_t p = 0; p < np; ++p) {
      const SegmentPatch& sp = seg.patches[p];
      auto uv = [&](std::uint32_t i, std::uint32_t j) {
        return Eigen::Vector2d(double(j) / (sp.cols - 1), double(i) / (sp.rows - 1));
      };
      auto add = [&](std::uint32_t i0, std::uint32_t j0, std::uint32_t i1, std::uint32_t j1) {
        const std::uint32_t v0 = sp.at(i0, j0), v1 = sp.at(i1, j1);
        if (v0 < v1)
          edges[{v0, v1}].push_back({p, uv(i0, j0), uv(i1, j1)});
        else
          edges[{v1, v0}].push_back({p, uv(i1, j1), uv(i0, j0)});
      };
      for (std::uint32_t j = 0; j + 1 < sp.cols; ++j) add(0, j, 0, j + 1), add(sp.rows - 1, j, sp.rows - 1, j + 1);
      for (std::uint32_t i = 0; i + 1 < sp.rows; ++i) add(i, 0, i + 1, 0), add(i, sp.cols - 1, i + 1, sp.cols - 1);
    }
    for (const auto& [e, sides] : edges) {
      if (sides.size() < 2) continue;
      ++stats->shared_edges;
      for (std::size_t x = 0; x < sides.size(); ++x)
        for (std::size_t y = x + 1; y < sides.size(); ++y)
          for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
            const Eigen::Vector2d ua = (1 - t) * sides[x].a + t * sides[x].b, ub = (1 - t) * sides[y].a + t * sides[y].b;
            const double gap = (surface_point(out.patches[sides[x].patch].surface, ua.x(), ua.y()) -
                                surface_point(out.patches[sides[y].patch].surface, ub.x(), ub.y()))
                                   .norm();
            if (gap > stats->boundary_gap_max) {
              stats->boundary_gap_max = gap;
              stats->boundary_gap_patch_a = sides[x].patch;
              stats->boundary_gap_patch_b = sides[y].patch;
            }
          }
    }
  }
  return out;
}

}  // namespace

Surfaces fit_surfaces(const Segments& seg, const FitBSplineOptions& o, FitStats* stats,
                      const std::function<void(double, const std::string&)>& progress, const Mesh* part) {
  Surfaces out = fit_patches(seg, o, stats, progress);
  if (!part) return out;
  if (o.subdivisions < 0) throw std::invalid_argument("subdivisions must not be negative");
  if (part->num_faces() == 0) throw std::invalid_argument("the part's mesh has no faces");
  std::vector<double> distance = surface_distance_max(out, *part);
  auto farthest = [](const std::vector<double>& d) { return d.empty() ? 0.0 : *std::max_element(d.begin(), d.end()); };
  const double before = farthest(distance);
  Segments finer;
  int level = 0;
  while (level < o.subdivisions && farthest(distance) > o.part_tolerance) {
    finer = subdivide_segments(level == 0 ? seg : finer, *part);
    ++level;
    if (progress) progress(0, "fitting B-spline patches to grids " + std::to_string(1 << level) + " times as fine");
    out = fit_patches(finer, o, stats, progress);
    distance = surface_distance_max(out, *part);
  }
  if (stats) {
    stats->subdivisions = level;
    stats->part_distance_before = before;
    stats->part_distance_after = farthest(distance);
    stats->part_distance = distance;
  }
  return out;
}

}  // namespace scallop
