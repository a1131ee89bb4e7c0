// Trimming a patch's steep rim: the part of a cloud a 3-axis ball-end finish can plan and
// certify, and what was left out.
//
// A patch whose rim turns steep (the chin of a face, the flanks of a cap cut low) folds its
// (u, v) map and its height-field fits there, and the whole patch is refused or planned with
// gouges on the rim. Trimming the points steeper than `max_slope_deg` (the angle of the PCA
// tangent plane to the xy plane) and keeping the largest connected piece of the rest gives a
// patch that can be planned; the trimmed band is reported as not machined, with its area and
// where it lies.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

struct TrimSteepOptions {
  double max_slope_deg = 90;  // points steeper than this are trimmed, (0, 90]; 90: no point is steep
  int k = 16;                 // neighbours of the PCA normals and of the connectivity, >= 3
};

// A connected piece of the trimmed band.
struct TrimmedRegion {
  std::size_t points = 0;
  double area = 0;  // mm², estimated surface area
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
  double max_slope_deg = 0;
};

struct TrimSteepResult {
  std::vector<std::size_t> kept;  // indices into P of the kept points, ascending
  std::size_t steep = 0;          // points steeper than max_slope_deg
  std::size_t cut_off = 0;        // gentle points left in smaller pieces than the largest
  double area = 0;                // mm², estimated surface area of the whole cloud
  double trimmed_area = 0;        // mm², of the points not kept
  double max_slope_kept_deg = 0;
  std::vector<TrimmedRegion> regions;  // pieces of the points not kept, largest area first (<= 10)
  // The k nearest neighbours of each kept point among the kept points, nearest first (what
  // cloud.knn computes on the trimmed cloud): the ones found for the trim when every point is
  // kept, computed again on the kept points otherwise.
  Neighborhoods neighbors;
};

// P  #P by 3 positions (mm), finite, #P > k.
// Each point's slope is acos |n_z| of its PCA normal over its k nearest neighbours; its area is
// pi d_k^2 / (k + 1), d_k the distance to its k-th neighbour (the disc its neighbourhood covers,
// shared by its k + 1 points). Kept: the largest connected component of the points not steeper
// than max_slope_deg (gentle), a gentle point joined to the gentle ones among its k nearest
// neighbours that are nearer than its nearest steep one (and symmetrically): gentle points beyond
// a steep band are not joined across it (noise near the limit, a row a scan left past a steep rim).
// Throws std::invalid_argument for bad options, too few points or degenerate neighbourhoods.
TrimSteepResult trim_steep(const std::vector<Eigen::Vector3d>& P, const TrimSteepOptions& options);

}  // namespace scallop
