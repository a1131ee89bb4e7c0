#include "nodes/param/harmonic.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cmath>
#include <future>
#include <memory>
#include <optional>
#include <utility>
#include <stdexcept>
#include <unsupported/Eigen/IterativeSolvers>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "nodes/param/boundary_map.h"
#include "nodes/param/two_level_solver.h"
#include "nodes/param/umfpack_lock.h"

namespace scallop {

HarmonicSolver parse_harmonic_solver(const std::string& name) {
  if (name == "two_level") return HarmonicSolver::TwoLevel;
  if (name == "direct") return HarmonicSolver::Direct;
  if (name == "bicgstab") return HarmonicSolver::BiCGSTAB;
  if (name == "gmres") return HarmonicSolver::GMRES;
  throw std::invalid_argument("unknown solver '" + name + "' (two_level, direct, bicgstab, gmres)");
}

namespace {

// Points the fixed ones are not reached from through the rows of L (their rows name only each
// other): the system is singular there. what(): the node's message for them.
struct UnreachedPoints : std::runtime_error {
  UnreachedPoints(const std::string& what, std::vector<int> p) : std::runtime_error(what), points(std::move(p)) {}
  std::vector<int> points;
};

constexpr double kMaxResidual = 1e-6;
// The two-level solver's relative residual: a map as exact as the direct LU's for the planner
// (tests/nodes/param/harmonic_test.cpp: (u,v) within 1e-8 of the domain's size of the direct
// solve's). bench/harmonic_solvers at a million points, 121 x 81 mm, both tolerances:
//   first 1e-9, map 1e-11: 40 + 37 GMRES iterations, (u,v) 2.3e-7 mm off the direct solve's;
//   first 1e-9, map 1e-10: 40 + 31, 7.5e-7 mm;
//   first 1e-8, map 1e-10: 34 + 31, 1.8e-6 mm (these);
//   first 1e-7, map 1e-10: 28 + 31, 6.9e-5 mm; first 1e-6: 1.3e-3 mm.
constexpr double kTwoLevelTolerance = 1e-10;
// The band solve's first map only measures how deep the band lies (band_depth_slope), and the
// second solve, to kTwoLevelTolerance from the first's answer, is the map; but the band's
// measured depth moves the map (above).
constexpr double kBandDepthTolerance = 1e-8;
// Below this many unknowns the direct LU is exact and takes under 0.2 s (bench/harmonic_solvers:
// 30 000 points 0.64 s direct, 0.27 s two-level; 8 000 points 0.12 s, 0.07 s). It stays there so
// that small clouds keep the map they had: a planner whose certificate sits at its limit can turn
// on a change of (u,v) of a few 1e-9 mm (the bundled example's gouge bound: 0.00996 direct,
// 0.01000 two-level, e = 0.01).
constexpr Eigen::Index kTwoLevelFrom = 50000;
const char* kSingular =
    "the harmonic map system is singular: some points are not connected to the outer boundary "
    "through their neighbours (a piece of the cloud apart from the patch? cloud.trim_steep keeps the "
    "largest connected piece and reports the rest)";

template <class Solver>
Eigen::MatrixXd solve_iterative(Solver& s, const Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& B,
                                const Eigen::MatrixXd& X0, const char* name) {
  s.setTolerance(1e-12);
  s.setMaxIterations(std::max<Eigen::Index>(1000, 4 * A.rows()));
  s.compute(A);
  if (s.info() != Eigen::Success)
    throw std::runtime_error(std::string(name) + ": the incomplete-LU preconditioner failed; " + kSingular);
  Eigen::MatrixXd X(B.rows(), B.cols());
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    X.col(c) = s.solveWithGuess(B.col(c), X0.col(c));
    if (s.info() != Eigen::Success)
      throw std::runtime_error(std::string(name) + " did not converge in " + std::to_string(s.iterations()) +
                               " iterations (error " + std::to_string(s.error()) + "); try solver=direct");
  }
  return X;
}

}  // namespace

namespace {

// The factors of an interior system, kept for a second solve with the same unknowns (the band
// solve fixes the same points twice, with other values), with the first solve's answer as the
// second's start.
struct SystemFactor {
  std::vector<char> given;            // #n: the points whose (u,v) is given
  std::vector<int> point_of;          // the point of each unknown, breadth first from the outer loop
  std::vector<Eigen::Index> unknown;
  Eigen::SparseMatrix<double, Eigen::RowMajor> rows;  // the system, rows in the unknowns' order
  Eigen::SparseMatrix<double> A;  // column-major copy for UMFPACK and Eigen's solvers
  std::unique_ptr<Eigen::UmfPackLU<Eigen::SparseMatrix<double>>> lu;
  std::unique_ptr<TwoLevelPreconditioner> two_level;  // built on `rows`
  bool two_level_failed = false;  // did not converge once: direct from then on
  Eigen::MatrixXd last;           // the last solution
};

// X of A X = B by UMFPACK's LU, factorised once per SystemFactor.
Eigen::MatrixXd solve_direct(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, const Eigen::MatrixXd& B,
                             SystemFactor& f) {
  std::lock_guard lock(umfpack_mutex());
  if (!f.lu) {
    f.A = A;
    f.lu = std::make_unique<Eigen::UmfPackLU<Eigen::SparseMatrix<double>>>();
    f.lu->compute(f.A);
    if (f.lu->info() != Eigen::Success) {
      f.lu.reset();
      throw std::runtime_error(kSingular);
    }
  }
  Eigen::MatrixXd X = f.lu->solve(B);
  if (f.lu->info() != Eigen::Success || !X.allFinite()) throw std::runtime_error(kSingular);
  return X;
}

// tolerance: the two-level solver's relative residual (the direct LU is exact).
UVMap solve_harmonic_reusing(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L, const UVMap& boundary,
                             HarmonicSolver solver,
                             const std::vector<std::pair<int, Eigen::Vector2d>>& fixed, SystemFactor* factor,
                             double tolerance) {
  const Eigen::Index n = L.rows();
  if (L.cols() != n) throw std::invalid_argument("the Laplacian is not square");
  const auto& outer = boundary.outer_loop;
  if (outer.size() < 3 || boundary.boundary_uv.size() != outer.size())
    throw std::invalid_argument("the boundary map has " + std::to_string(outer.size()) + " loop points and " +
                                std::to_string(boundary.boundary_uv.size()) + " boundary positions");
  // Unknown index of every point, -1 on the outer loop.
  std::vector<Eigen::Index> unknown(n, 0);
  std::vector<Eigen::Vector2d> uv(n, Eigen::Vector2d::Zero());
  for (std::size_t j = 0; j < outer.size(); ++j) {
    int i = outer[j];
    if (i < 0 || i >= n)
      throw std::invalid_argument("the outer loop has point index " + std::to_string(i) +
                                  " outside the Laplacian's " + std::to_string(n) + " points");
    if (unknown[i] < 0) throw std::invalid_argument("the outer loop visits point " + std::to_string(i) + " twice");
    unknown[i] = -1;
    uv[i] = boundary.boundary_uv[j];
  }
  for (const auto& [i, q] : fixed) {
    if (i < 0 || i >= n)
      throw std::invalid_argument("a fixed point index " + std::to_string(i) + " is outside the Laplacian's " +
                                  std::to_string(n) + " points");
    unknown[i] = -1;
    uv[i] = q;
  }
  // Unknowns numbered breadth first from the outer loop, so that a row's neighbours are near it
  // in memory whatever order the cloud came in (the same points fixed: the numbering before).
  std::vector<char> given(n);  // the points whose (u,v) is fixed
  for (Eigen::Index i = 0; i < n; ++i) given[i] = unknown[i] < 0;
  const bool same_unknowns = factor && factor->given == given;
  std::vector<int> point_of;  // #unknowns: the point of each unknown
  if (same_unknowns) {
    unknown = factor->unknown;
    point_of = factor->point_of;
  } else {
    for (int i : breadth_first_order(L, outer))
      if (unknown[i] >= 0) {
        unknown[i] = static_cast<Eigen::Index>(point_of.size());
        point_of.push_back(i);
      }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(point_of.size());

  // Every unknown must reach the outer loop through its rows' neighbours; otherwise its cluster's
  // rows (summing to zero) make the system singular, which rounding can hide from the LU. (Checked
  // once for the same unknowns: the band's second solve; beside the preconditioner's build, below.)
  auto check_connected = [&] {
    // The rows that depend on each point j (L's nonzero pattern transposed, indices only).
    std::vector<int> start(n + 1, 0), dependent;
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(L, i); it; ++it)
        if (it.col() != i && it.value() != 0) ++start[it.col() + 1];
    for (Eigen::Index j = 0; j < n; ++j) start[j + 1] += start[j];
    dependent.resize(start[n]);
    {
      std::vector<int> next(start.begin(), start.end() - 1);
      for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(L, i); it; ++it)
          if (it.col() != i && it.value() != 0) dependent[next[it.col()]++] = static_cast<int>(i);
    }
    std::vector<char> reached(n, 0);
    std::vector<int> stack;
    for (Eigen::Index i = 0; i < n; ++i)
      if (unknown[i] < 0) reached[i] = 1, stack.push_back(static_cast<int>(i));
    while (!stack.empty()) {
      const int j = stack.back();
      stack.pop_back();
      for (int e = start[j]; e < start[j + 1]; ++e)
        if (!reached[dependent[e]]) reached[dependent[e]] = 1, stack.push_back(dependent[e]);
    }
    std::vector<int> cut;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!reached[i]) cut.push_back(static_cast<int>(i));
    if (!cut.empty()) {
      const std::string what = std::to_string(cut.size()) + " points (first: point " + std::to_string(cut[0]) +
                               ") are not connected to the outer boundary through their neighbours, so "
                               "their (u,v) is undefined (a piece of the cloud apart from the patch? "
                               "cloud.trim_steep keeps the largest connected piece and reports the rest)";
      throw UnreachedPoints(what, std::move(cut));
    }
  };
  std::optional<std::future<void>> connected;
  if (!same_unknowns) connected = std::async(std::launch::async, check_connected);
  // Its answer before any solve's: an unconnected system's solve fails with a less clear message.
  auto wait_connected = [&] {
    if (connected) std::exchange(connected, std::nullopt)->get();
  };

  UVMap out = boundary;
  out.residual = 0;
  if (m == 0) wait_connected();
  if (m > 0) {
    SystemFactor local;
    SystemFactor& f = factor ? *factor : local;
    // Same unknowns, same rows of L: the same matrix, so it and its factors can be used again.
    if (f.given != given) {
      f = SystemFactor();
      f.given = given;
      f.unknown = unknown;
      f.point_of = point_of;
    }
    // A X = B: the interior rows of L, boundary columns moved to the right-hand side; written
    // straight into the compressed rows, the rows in parallel (each row's sums in L's order, as
    // one after the other would give).
    const bool build = f.rows.rows() != m;
    using RowIt = Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator;
    if (build) {
      f.rows.resize(m, m);  // compressed, no entries
      int* outer = f.rows.outerIndexPtr();
      tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index r) {
        int count = 0;
        for (RowIt it(L, point_of[r]); it; ++it) count += unknown[it.col()] >= 0;
        outer[r + 1] = count;
      });
      for (Eigen::Index r = 0; r < m; ++r) outer[r + 1] += outer[r];
      f.rows.resizeNonZeros(outer[m]);
    }
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(m, 2);
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, 1024), [&](const auto& range) {
      std::vector<std::pair<int, double>> row;
      for (Eigen::Index r = range.begin(); r != range.end(); ++r) {
        row.clear();
        for (RowIt it(L, point_of[r]); it; ++it) {
          const Eigen::Index j = it.col();
          if (unknown[j] < 0)
            B.row(r) -= it.value() * uv[j].transpose();
          else if (build)
            row.emplace_back(static_cast<int>(unknown[j]), it.value());
        }
        if (!build) continue;
        std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        int e = f.rows.outerIndexPtr()[r];
        for (const auto& [c, v] : row) f.rows.innerIndexPtr()[e] = c, f.rows.valuePtr()[e++] = v;
      }
    });
    const Eigen::SparseMatrix<double, Eigen::RowMajor>& A = f.rows;
    // Start from the last solution, or the mean of the boundary positions (the interior values
    // are averages of them).
    Eigen::MatrixXd X0 = f.last;
    if (X0.rows() != m) {
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const auto& q : boundary.boundary_uv) mean += q;
      mean /= static_cast<double>(outer.size());
      X0.resize(m, 2);
      X0.col(0).setConstant(mean.x());
      X0.col(1).setConstant(mean.y());
    }
    Eigen::MatrixXd X;
    if (solver == HarmonicSolver::TwoLevel && m >= kTwoLevelFrom && !f.two_level_failed) {
      if (!f.two_level) {
        f.two_level = std::make_unique<TwoLevelPreconditioner>();
        if (!f.two_level->build(A)) f.two_level_failed = true;
      }
      wait_connected();
      if (!f.two_level_failed) {
        TwoLevelResult r = solve_two_level(A, *f.two_level, B, X0, tolerance);
        if (r.converged && r.X.allFinite())
          X = std::move(r.X);
        else
          f.two_level_failed = true;
      }
      if (f.two_level_failed) f.two_level.reset();
    }
    wait_connected();
    if (X.size() == 0 && (solver == HarmonicSolver::Direct || solver == HarmonicSolver::TwoLevel)) {
      X = solve_direct(A, B, f);
    } else if (X.size() == 0) {
      if (f.A.rows() != m) f.A = A;
      if (solver == HarmonicSolver::BiCGSTAB) {
        Eigen::BiCGSTAB<Eigen::SparseMatrix<double>, Eigen::IncompleteLUT<double>> s;
        X = solve_iterative(s, f.A, B, X0, "BiCGSTAB");
      } else {
        Eigen::GMRES<Eigen::SparseMatrix<double>, Eigen::IncompleteLUT<double>> s;
        s.set_restart(50);
        X = solve_iterative(s, f.A, B, X0, "GMRES");
      }
    }
    f.last = X;
    double bnorm = B.norm();
    out.residual = (A * X - B).norm() / (bnorm > 0 ? bnorm : 1.0);
    if (!(out.residual <= kMaxResidual))
      throw std::runtime_error("the harmonic map solve is inaccurate: relative residual " +
                               std::to_string(out.residual) + " > 1e-6; " + kSingular);
    for (Eigen::Index i = 0; i < n; ++i)
      if (unknown[i] >= 0) uv[i] = X.row(unknown[i]).transpose();
  }
  for (std::size_t j = 0; j < outer.size(); ++j) out.boundary_uv[j] = uv[outer[j]];
  out.uv = std::move(uv);
  return out;
}

// solve(L), and where points are not reached through their rows and join is given, solve(join(them)).
template <class Solve>
UVMap solve_joining_unreached(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L, const JoinRows& join,
                              const Solve& solve) {
  try {
    return solve(L);
  } catch (const UnreachedPoints& e) {
    if (!join) throw;
    return solve(join(e.points));
  }
}

}  // namespace

UVMap solve_harmonic(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L, const UVMap& boundary,
                     HarmonicSolver solver,
                     const std::vector<std::pair<int, Eigen::Vector2d>>& fixed, const JoinRows& join) {
  return solve_joining_unreached(L, join, [&](const Eigen::SparseMatrix<double, Eigen::RowMajor>& A) {
    return solve_harmonic_reusing(A, boundary, solver, fixed, nullptr, kTwoLevelTolerance);
  });
}

UVMap solve_harmonic_band(const Eigen::SparseMatrix<double, Eigen::RowMajor>& L,
                          const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                          const std::vector<std::uint8_t>& is_boundary,
                          const std::vector<std::vector<int>>& loops, const UVMap& boundary,
                          HarmonicSolver solver,
                          const std::function<void(double, const std::string&)>& progress, const JoinRows& join) {
  if (static_cast<std::size_t>(L.rows()) != P.size())
    throw std::invalid_argument("the Laplacian has " + std::to_string(L.rows()) + " rows but the cloud has " +
                                std::to_string(P.size()) + " points");
  const std::vector<BandPoint> band = outer_band(P, N, is_boundary, loops, boundary.outer_loop, boundary.corners);
  const std::vector<Eigen::Vector2d> zero(boundary.outer_loop.size(), Eigen::Vector2d::Zero());
  return solve_joining_unreached(L, join, [&](const Eigen::SparseMatrix<double, Eigen::RowMajor>& A) {
    SystemFactor factor;  // both solves usually fix the same points: one factorisation
    if (progress)
      progress(0.05, "first solve, the band on the domain's edge (" + std::to_string(A.rows()) +
                         " points; the sparse factorisation takes most of the time)");
    UVMap first =
        solve_harmonic_reusing(A, boundary, solver, band_values(band, boundary, zero), &factor, kBandDepthTolerance);
    if (progress) progress(0.6, "second solve, the band at its measured depth");
    UVMap out = solve_harmonic_reusing(
        A, boundary, solver, band_values(band, boundary, band_depth_slope(band, boundary, first.uv)), &factor,
        kTwoLevelTolerance);
    if (progress) progress(1.0, "solved");
    return out;
  });
}

}  // namespace scallop
