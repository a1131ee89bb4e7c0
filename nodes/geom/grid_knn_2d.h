// Exact k nearest neighbours of planar points through a uniform grid of buckets.
//
// For queries in a set spread over a region (the (u,v) images of a cloud): the cells around the
// query are visited ring by ring, and the search stops once no cell farther out can hold a point
// nearer than the k-th found. About 2 points per cell; for k of 10 to 64 this visits a few tens
// of cells, with none of a tree's descent and backtracking.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace scallop {

class GridKnn2d {
 public:
  // P  #P planar points, finite (copied: the grid keeps its own, ordered by cell).
  // Throws std::invalid_argument for an empty set or a non-finite coordinate.
  explicit GridKnn2d(const std::vector<Eigen::Vector2d>& P);
  // The same over the (x, y) of 3-D points (indices into P as above).
  explicit GridKnn2d(const std::vector<Eigen::Vector3d>& P);

  // The min(k, #P) points nearest q (any finite q, inside the points' bounds or not), nearest
  // first, equal distances by index: idx their indices into P, sq their squared distances; both
  // resized to that count. k >= 1.
  void query(const Eigen::Vector2d& q, int k, std::vector<std::uint32_t>& idx, std::vector<double>& sq) const;
  // The same into caller arrays of at least k entries (no allocation); returns the count.
  int query(const Eigen::Vector2d& q, int k, std::uint32_t* idx, double* sq) const;

  std::size_t size() const { return index_.size(); }

 private:
  template <class Point>
  void build(const std::vector<Point>& P);
  int column_of(double x, double origin, int count) const;  // the cell index along one axis
  double x0_ = 0, y0_ = 0, cell_ = 1;  // the grid's corner and cell side
  double slack_ = 0;                   // more than the rounding of a point into its cell
  int nx_ = 1, ny_ = 1;
  std::vector<std::uint32_t> start_;  // nx * ny + 1: each cell's first entry
  std::vector<Eigen::Vector2d> point_; // the points, cell by cell
  std::vector<std::uint32_t> index_;   // their indices into P
};

}  // namespace scallop
