// Weighted K-means of 3-D points (Lloyd's iterations from k-means++ seeds), deterministic: the
// seeds come from a fixed generator, so the same points give the same clusters on every machine.
// mesh.setup_base clusters face normals with it (papers/point-clouds-to-workpieces.md).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace scallop {

struct KMeansOptions {
  int k = 6;                 // clusters asked for
  std::uint32_t seed = 1;    // of the k-means++ seeding (std::mt19937, its raw output only)
  int restarts = 4;          // seedings tried (seed, seed + 1, ...); the lowest inertia is kept
  int max_iterations = 100;  // Lloyd iterations per seeding (it stops earlier when no label changes)
};

// centre   #C weighted means of the clusters' points (C <= k: fewer when the points have fewer
//          than k distinct positions; never an empty cluster), heaviest cluster first (ties: by
//          centre, lexicographically), so the order does not depend on the seeding
// weight   #C sum of the weights of each cluster's points
// size     #C number of points in each cluster
// label    #P cluster of each point (its nearest centre; ties to the lower index)
// inertia  sum over the points of weight * squared distance to their centre
struct KMeansResult {
  std::vector<Eigen::Vector3d> centre;
  std::vector<double> weight;
  std::vector<std::size_t> size;
  std::vector<int> label;
  double inertia = 0;
};

// points   #P by 3, finite
// weights  #P non-negative weights with a positive sum (a point of weight 0 is labelled but does
//          not move a centre), or empty: every weight 1
// k-means++ seeding: the first centre is drawn with probability proportional to the weight, each
// next one proportional to weight * squared distance to the nearest centre so far; Lloyd's
// iterations then alternate nearest-centre labels and weighted means.
// Throws std::invalid_argument for no points, k < 1, weights of another length or negative, or
// all zero.
KMeansResult kmeans(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& weights,
                    const KMeansOptions& options);

}  // namespace scallop
