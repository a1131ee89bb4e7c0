// nanoflann k-d trees over vectors of fixed-size Eigen points, read in place (no copy).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nanoflann.hpp>
#include <vector>

namespace scallop {

// Adaptor over a vector of Eigen points. A tree of dimension Dim searches the first Dim
// coordinates, so KdTree<Eigen::Vector3d, 2> searches 3-D points by their xy.
template <class Point>
struct PointsAdaptor {
  const std::vector<Point>& pts;
  std::size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return pts[i][static_cast<int>(d)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

// The squared distance as the trees' metric (L2_Simple_Adaptor) sums it, x then y then z: a test
// made outside a tree, on points it found, agrees with the tree's to the last bit.
inline double tree_distance2(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const double diff = a[i] - b[i];
    d2 += diff * diff;
  }
  return d2;
}

template <class Point, int Dim>
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, PointsAdaptor<Point>, double, std::uint32_t>, PointsAdaptor<Point>, Dim,
    std::uint32_t>;

// Adaptor over some of a vector's points, named by their indices (no copy of the points): the
// tree reports the position in `subset`, subset[i] is the point's index in `pts`.
template <class Point>
struct SubsetAdaptor {
  const std::vector<Point>& pts;
  const std::vector<std::uint32_t>& subset;
  std::size_t kdtree_get_point_count() const { return subset.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return pts[subset[i]][static_cast<int>(d)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

template <class Point, int Dim>
using KdSubsetTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, SubsetAdaptor<Point>, double, std::uint32_t>, SubsetAdaptor<Point>, Dim,
    std::uint32_t>;

// A nanoflann result set that keeps every index within a radius, unsorted (cheaper than the
// sorted matches of radiusSearch): tree.findNeighbors(set, query, nanoflann::SearchParams(32, 0,
// false)). radius2 is the radius squared; out is cleared first.
struct CollectWithin {
  double radius2;
  std::vector<std::uint32_t>* out;
  void init() {}
  void clear() { out->clear(); }
  std::size_t size() const { return out->size(); }
  bool full() const { return true; }
  bool addPoint(double d2, std::uint32_t i) {
    if (d2 < radius2) out->push_back(i);
    return true;
  }
  double worstDist() const { return radius2; }
};

}  // namespace scallop
