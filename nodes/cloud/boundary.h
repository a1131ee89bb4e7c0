// Boundary points of an open patch by the largest angular gap between its neighbours (the
// criterion of PCL's BoundaryEstimation; paper section 2.2: "a point cloud is classified into two
// subsets, interior and boundary").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

// P      #P by 3 positions (mm)
// N      #P by 3 unit normals
// nbrs   k >= 3 neighbours per point (self excluded)
// angle  gap threshold (radians): a point is on the boundary when the largest angle between
//        consecutive neighbour directions, projected on its tangent plane, exceeds it
// clean  second pass against noise: boundary points with fewer than 2 boundary points among
//        their neighbours are isolated false positives and become interior
// Returns #P flags, 1 for boundary points.
//
// Why two tests: with k = 12 on a random (Poisson-like) sampling the 12 neighbour directions of
// an interior point leave a largest gap of about 2 pi / 12 * H_12 = 93 degrees on average (H the
// harmonic number), so the plain k-neighbour test flags about half of all points. The gap over
// the two-ring (neighbours and their neighbours, ~40 points) is about 40 degrees inside and stays
// near 180 degrees on the boundary, so it rejects the false positives; the one-ring test keeps
// the flagged band thin (only points within ~0.7 neighbour radius of the edge pass it).
// A point is on the boundary when both gaps exceed `angle`.
// progress: optional, called with the fraction done, in [0, 1].
// Throws std::invalid_argument for mismatched sizes (normals missing), k < 3 or bad indices.
std::vector<std::uint8_t> detect_boundary(const std::vector<Eigen::Vector3d>& P,
                                          const std::vector<Eigen::Vector3d>& N,
                                          const Neighborhoods& nbrs, double angle, bool clean = true,
                                          const std::function<void(double)>& progress = {});

// Whether the largest angular gap (radians, in [0, 2 pi]) between the directions from P[i] to the
// points `around`, projected on the plane through P[i] normal to `normal`, exceeds `angle`; the
// gap is 2 pi when no point has a tangential component.
bool angular_gap_exceeds(const std::vector<Eigen::Vector3d>& P, const Eigen::Vector3d& normal, std::size_t i,
                         const std::vector<int>& around, double angle);

}  // namespace scallop
