// Small synthetic clouds and a one-call parameterisation pipeline for the param tests.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/boundary_order.h"
#include "nodes/cloud/knn.h"
#include "nodes/param/boundary_map.h"
#include "nodes/param/harmonic.h"
#include "nodes/param/laplacian.h"
#include "nodes/types/cloud.h"

namespace scallop::test {

// Uniform random points in the disk of radius r in the plane z = 0, normals +Z.
inline PointCloud random_disk(int n, double r, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-r, r);
  PointCloud c;
  while (static_cast<int>(c.points.size()) < n) {
    double x = u(rng), y = u(rng);
    if (x * x + y * y <= r * r) c.points.emplace_back(x, y, 0.0);
  }
  c.normals.assign(c.points.size(), Eigen::Vector3d::UnitZ());
  return c;
}

// Jittered grid on [0, w] x [0, h], spacing dx by dy, jitter a fraction of the spacing; normals +Z.
inline PointCloud jittered_grid(double w, double h, double dx, double dy, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  PointCloud c;
  const int nx = static_cast<int>(std::lround(w / dx)), ny = static_cast<int>(std::lround(h / dy));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      double x = i * dx, y = j * dy;
      // Keep the outline straight: jitter only along the edge on edge points.
      if (i > 0 && i < nx) x += jitter * dx * u(rng);
      if (j > 0 && j < ny) y += jitter * dy * u(rng);
      c.points.emplace_back(x, y, 0.0);
    }
  c.normals.assign(c.points.size(), Eigen::Vector3d::UnitZ());
  return c;
}

struct Pipeline {
  Neighborhoods nbrs;
  std::vector<std::uint8_t> is_boundary;
  std::vector<std::vector<int>> loops;
  UVMap map;
};

// cloud.knn -> cloud.boundary -> cloud.boundary_order -> param.boundary_map -> param.laplacian
// -> param.harmonic (with the boundary band fixed, as the node does by default), with the
// algorithm functions.
inline Pipeline parameterize(const PointCloud& c, int k, BoundaryDomain domain,
                             LaplacianScheme scheme = LaplacianScheme::Optimal,
                             HarmonicSolver solver = HarmonicSolver::Direct) {
  Pipeline p;
  p.nbrs = compute_knn(c.points, k);
  p.is_boundary = detect_boundary(c.points, c.normals, p.nbrs, std::numbers::pi / 2);
  p.loops = order_boundary_loops(c.points, c.normals, p.nbrs, p.is_boundary);
  UVMap b = map_boundary(c.points, p.loops[0], domain);
  auto L = build_laplacian(c.points, c.normals, p.nbrs, scheme);
  p.map = solve_harmonic_band(L, c.points, c.normals, p.is_boundary, p.loops, b, solver);
  return p;
}

}  // namespace scallop::test
