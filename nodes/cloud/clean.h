// Cleaning of a raw point cloud: non-finite points, exact duplicates, statistical outliers.
#pragma once

#include <cstddef>

#include "nodes/types/cloud.h"

namespace scallop {

struct CleanOptions {
  bool remove_outliers = false;
  int outlier_k = 16;              // neighbours whose mean distance rates a point
  double outlier_std_ratio = 2.0;  // outlier: mean distance > global mean + ratio * std
  bool remove_stray = false;       // drop points off the surface their neighbours sample
  int stray_k = 16;                // neighbours whose quadric judges a point
  bool spatial_order = true;       // the points kept along a space-filling curve
                                   // (geom/spatial_order.h), else in their original order
};

// Point counts: input = non_finite + duplicates + outliers + stray + output.
struct CleanStats {
  std::size_t input = 0, non_finite = 0, duplicates = 0, outliers = 0, stray = 0, output = 0;
};

// in  #P points (mm), with or without normals.
// Returns the points that survive, with their normals if `in` has them, along a space-filling
// curve (opts.spatial_order: neighbours near one another in memory, which every later per-point
// pass over neighbourhoods runs faster for) or in their original order:
//  1. points with a NaN or infinite coordinate, or a NaN or infinite normal, are dropped;
//  2. of points with exactly equal coordinates only the first (lowest index) is kept
//     (lexicographic sort, O(#P log #P));
//  3. if opts.remove_outliers, statistical outlier removal as PCL's StatisticalOutlierRemoval
//     defines it (Rusu et al., "Towards 3D point cloud based object maps for household
//     environments", 2008): d_i = mean Euclidean distance of point i to its outlier_k nearest
//     neighbours, mu and sigma the mean and sample standard deviation (n - 1) of all d_i; point i
//     is an outlier if d_i > mu + outlier_std_ratio * sigma. Run on the points left by 1-2;
//  4. if opts.remove_stray, the points off the surface their stray_k nearest sample
//     (stray_points.h), on the points left by 1-3.
// Throws std::invalid_argument when outlier removal is asked for with outlier_k < 1 or with no
// more than outlier_k points left, and the same for stray_k (at least 8).
PointCloud clean_cloud(const PointCloud& in, const CleanOptions& opts,
                       CleanStats* stats = nullptr);

}  // namespace scallop
