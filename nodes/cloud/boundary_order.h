// Ordering boundary points into closed loops, outer loop first, without manual breaking points
// (the paper, section 2.2, breaks the boundary by hand; we do not).
//
// Method: link every boundary point to its nearest boundary points (within twice the local
// neighbourhood radius), take the minimum spanning forest of that graph (where the links within
// one radius already close a loop, its links longer than that to another loop's points are left
// out: they cross the part, e.g. between a hole and the outline), and for each tree:
// its longest path runs once around the loop (a tree of points sampled along a closed curve is
// the curve cut open at one place); the points off that path (the boundary band is a few points
// thick on a noisy cloud) are inserted next to their tree parent on the cheaper side, and a
// windowed 2-opt removes the remaining local zig-zags. Off-path points that would lengthen the
// loop by more than their neighbourhood radius (spurs towards false boundary points inside the
// patch) stay off the loop but keep their boundary flag; a subtree left out that is itself a
// stretch of the loop (three long links or more, hanging off the longest path where the loop's
// points leave gaps) goes into the loop whole, along its own longest path, where joining its ends
// costs least, and so does a tree of its own that encloses nearly nothing but runs three long
// links from end to end (a stretch cut off by gaps at both ends). Nothing assumes a convex or star-shaped
// outline, nor uniform spacing. Hole loops enclosing less than pi (2 r)^2, r the mean
// neighbourhood radius of their points, are sampling voids and are dropped.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

// P            #P by 3 positions (mm)
// N            #P by 3 unit normals, or empty; used only to orient the loops
// nbrs         k neighbours per point (self excluded); the k-th distance sets the link radius
// is_boundary  #P flags (detect_boundary)
// min_loop_points  components with fewer points are dropped as noise
// Returns closed loops of point indices (first index not repeated at the end). Loop 0 is the
// outer loop: the one enclosing the largest area projected on the least-squares plane of the
// cloud. Loops are oriented so the patch lies on their left seen from the normals' side (the
// plane normal is oriented along the sum of N, or towards +Z without normals): the outer loop
// counter-clockwise, holes clockwise.
// Throws std::invalid_argument "no boundary points found: the cloud looks closed (a 3-axis
// finishing path needs an open patch)" when no point is flagged, a message naming
// min_loop_points when every component is smaller, and for mismatched sizes.
std::vector<std::vector<int>> order_boundary_loops(const std::vector<Eigen::Vector3d>& P,
                                                   const std::vector<Eigen::Vector3d>& N,
                                                   const Neighborhoods& nbrs,
                                                   const std::vector<std::uint8_t>& is_boundary,
                                                   int min_loop_points = 8);

// Signed area (mm^2) of a closed loop projected on the plane through c with unit normal n;
// positive when counter-clockwise seen from the side n points to.
double projected_loop_area(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                           const Eigen::Vector3d& c, const Eigen::Vector3d& n);

}  // namespace scallop
