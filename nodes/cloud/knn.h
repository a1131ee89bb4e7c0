// k nearest neighbours of every point of a cloud (nanoflann k-d tree, queries in parallel).
//
// nanoflann was measured against PCL's FLANN k-d tree on 1M points, k = 12
// (bench/knn_backends_bench.cpp): with queries in the tree's leaf order, as here, build + query
// take 1.8 s CPU against 4.1 s for PCL queried in index order (2.2 s even given a coherent
// order). It is header-only, kept out of this header (pimpl); PCL stays out of the product.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <functional>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

// P  #P by 3 positions (mm), all finite;  k  neighbours per point, 1 <= k < #P.
// Returns the k nearest other points of every point, nearest first, equal distances ordered by
// increasing index. The point itself is excluded by index, not by distance, so an exact
// duplicate of a point is its neighbour at squared distance 0.
// Throws std::invalid_argument for k < 1, k >= #P ("k = 12 needs at least 13 points; the cloud
// has 5"), #P >= 2^31, or a non-finite coordinate.
// progress  optional, called with the fraction of the queries done, in [0, 1].
Neighborhoods compute_knn(const std::vector<Eigen::Vector3d>& P, int k,
                          const std::function<void(double)>& progress = {});

// A k-d tree over fixed points for queries at arbitrary positions (e.g. projecting tool
// positions onto the cloud). Keeps a reference to P: P must outlive the index and not change.
// Queries are const and thread-safe.
class KnnIndex {
 public:
  // Throws std::invalid_argument for an empty P, #P >= 2^31 or a non-finite coordinate.
  explicit KnnIndex(const std::vector<Eigen::Vector3d>& P);
  ~KnnIndex();
  KnnIndex(const KnnIndex&) = delete;
  KnnIndex& operator=(const KnnIndex&) = delete;

  std::size_t size() const;

  // The min(k, #P) points of P nearest to q (minus `skip`, an index of P to exclude, or -1),
  // nearest first, ties by increasing index. idx/sq_dist are resized to the count found.
  void query(const Eigen::Vector3d& q, int k, std::vector<int>& idx, std::vector<double>& sq_dist,
             int skip = -1) const;

  // The points of P (minus `skip`) within squared distance sq_radius of q, the k nearest of them
  // when there are more, in query()'s order. With sq_radius = kth_sq_distance(q, k, skip) it
  // gives what query(q, k, ...) gives, in less time (the search knows its radius from the start).
  // in_order false: the same points in the search's own order (deterministic, not by distance),
  // for callers that only sum over them (putting a thousand in order costs more than finding them).
  void query_within(const Eigen::Vector3d& q, double sq_radius, int k, std::vector<int>& idx,
                    std::vector<double>& sq_dist, int skip = -1, bool in_order = true) const;

  // The squared distance from q to the k-th nearest point of P (minus `skip`), as query() would
  // give it last, without putting the k in order; 0 when there are none. guess > 0: a squared
  // distance the k-th is likely within (a neighbour's: the points within it are searched first,
  // and the k nearest only when fewer are found); the same answer either way.
  double kth_sq_distance(const Eigen::Vector3d& q, int k, int skip = -1, double guess = 0) const;

  // Index of the point of P nearest to q (ties: lowest index).
  int nearest(const Eigen::Vector3d& q) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scallop
