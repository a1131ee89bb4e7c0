// Denoising a point cloud by moving-least-squares (MLS) projection onto local quadrics.
//
// Every point q is projected onto a smooth surface fitted to its neighbourhood (Levin, "Mesh-
// independent surface interpolation", 2003; Alexa, Behr, Cohen-Or, Fleishman, Levin, Silva,
// "Computing and rendering point set surfaces", IEEE TVCG 2003, section 3):
//   1. a reference plane H through the Gaussian-weighted centroid of the neighbours, with the
//      normal n of the smallest eigenvalue of their weighted covariance (weights centred at q);
//   2. a local frame (t1, t2, n) with its origin at q, and the weighted least-squares quadric
//      w = a + b u + c v + d u^2 + e u v + f v^2 over the neighbours' frame coordinates (u, v, w);
//   3. q moves to the quadric point above (u, v) = (0, 0): q' = q + a n, the normal of the
//      quadric there being proportional to n - b t1 - c t2.
// Here the plane is taken in one step (the weighted PCA plane) rather than by Levin's non-linear
// minimisation; the quadric absorbs the offset between q and the plane. A point therefore only
// ever moves along its local normal: one-sided neighbourhoods at the boundary of the cloud cannot
// pull it inwards, and the sampling in the tangent plane is kept.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

struct DenoiseOptions {
  int k = 64;              // neighbours in each fit (the point itself excluded), >= 5
  double radius = 0;       // mm; > 0: only neighbours within radius, Gaussian width radius / 2;
                           // 0: per point, Gaussian width half the distance to its k-th neighbour
  int iterations = 1;      // projections in sequence, each on the result of the previous one
  bool set_normals = true; // output normals from the quadric's gradient
};

struct DenoiseResult {
  std::vector<Eigen::Vector3d> points;   // #P moved positions (mm)
  std::vector<Eigen::Vector3d> normals;  // #P unit normals, or empty when !set_normals
  std::size_t kept = 0;  // points left in place in the last iteration (degenerate neighbourhood)
};

// P      #P by 3 positions (mm), all finite
// N      #P by 3 unit normals, or empty: only used to orient the output normals (the fitted
//        normal is flipped to agree with N_i, or with +Z when N is empty)
// nbrs   optional neighbourhoods of P (e.g. compute_knn(P, k)); when given, the first
//        min(k, nbrs.k) neighbours of each point are used in every iteration, with distances
//        recomputed from the moved positions. When null, a k-d tree is built over the current
//        positions in each iteration (k is clamped to #P - 1).
// progress  optional, called with the fraction done in [0, 1].
// A point whose neighbourhood is degenerate (fewer than 6 points with weight, all collinear, or a
// singular quadric fit) is kept as it is (and its normal taken from N, or +Z when N is empty).
// Throws std::invalid_argument for an empty cloud ("the cloud is empty"), a non-finite
// coordinate, N or nbrs not matching P, k < 5, radius < 0 or non-finite, iterations < 0.
DenoiseResult mls_denoise(const std::vector<Eigen::Vector3d>& P,
                          const std::vector<Eigen::Vector3d>& N, const DenoiseOptions& options,
                          const Neighborhoods* nbrs = nullptr,
                          const std::function<void(double)>& progress = {});

}  // namespace scallop
