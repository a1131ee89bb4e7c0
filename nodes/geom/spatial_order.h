// Points in the order of a space-filling curve, so that points near one another in space are near
// one another in memory.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace scallop {

// The permutation that sorts P along the Z-order (Morton) curve of a 2^21-cell-per-axis grid over
// P's bounding box (ties: by index, so the order is deterministic).
// P  #P by 3 positions, finite.
// Returns #P distinct indices of P: order[0] is the first point along the curve.
// A cloud stored so reads its neighbourhoods from nearby memory: every per-point pass over its
// neighbours (KNN, normals, Laplacian, the harmonic solve's sweeps) then runs from the cache
// instead of main memory (a million points in random order: 2 to 4 times slower).
std::vector<std::size_t> spatial_order(const std::vector<Eigen::Vector3d>& P);

}  // namespace scallop
