// Diagnostics of a (u,v) map of a point cloud: angle distortion (how far from conformal) and
// fold-overs (where the map reverses orientation).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

struct MapCheck {
  // sigma1 / sigma2 >= 1 of the least-squares Jacobian (tangent plane -> uv) at each point;
  // 1 is conformal; +infinity where the local map is degenerate.
  std::vector<double> distortion;
  std::vector<std::uint8_t> folded;  // #P, 1 where the map reverses orientation
  std::size_t foldovers = 0;         // number of folded points
  int first_foldover = -1;           // lowest folded index, -1 if none
  // {"points", "conformality": {"measure", "mean", "p50", "p95", "max",
  //   "histogram": {"edges", "counts"}}, "foldovers", "first_foldover": null | {"index",
  //   "position": [x,y,z]}, "flipped_fan_triangles", "points_with_a_flipped_fan_triangle"}
  nlohmann::json report;
};

// P     #P by 3 positions (mm);  N  #P by 3 unit normals (the orientation reference)
// nbrs  k >= 2 neighbours per point (self excluded)
// uv    #P parameter positions
// Angle distortion at p_i: J (2x2) fitted by least squares to uv_j - uv_i = J x_j over the
// neighbours, x_j the tangent-plane coordinates of p_j - p_i; reported as sigma1/sigma2 of J.
// Fold-over at p_i: the neighbours are sorted by angle in the tangent plane; each pair of
// consecutive neighbours a, b that spans between 10 and 170 degrees at p_i forms a triangle
// (p_i, a, b) that is counter-clockwise seen from n_i. p_i is folded when its Jacobian J has a
// negative determinant or when more than half of those fan triangles are clockwise in uv. (A
// single flipped sliver of the fan happens in valid maps of anisotropic samplings: the fan is not
// a triangulation, and a thin triangle flips under a sub-spacing wiggle. Its count is reported as
// "flipped_fan_triangles" all the same.)
// Throws std::invalid_argument for mismatched sizes or missing normals.
MapCheck check_map(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                   const Neighborhoods& nbrs, const std::vector<Eigen::Vector2d>& uv);

// "the (u,v) map folds over at N points (first near x, y, z): ..." for a check with fold-overs.
std::string foldover_message(const MapCheck& check, const std::vector<Eigen::Vector3d>& P);

}  // namespace scallop
