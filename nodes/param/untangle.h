// Local untangling of a (u,v) map that folds over at a few points.
//
// A discrete harmonic map can fold where the sampling is thin against the shape: a sharp spike
// a few samples wide, a corner of the outline next to the boundary band. There a handful of
// points land on the wrong side of their neighbours. Each such point (and the neighbours around
// it) is moved to the mean (u,v) of its neighbours, a convex combination, which is what a
// harmonic map with uniform weights asks of it and which cannot fold on its own (Tutte); the
// region grows by one ring of neighbours each round until check_map finds no fold-over. Points of
// the outer loop in the region slide along the domain's edge instead: to the edge point nearest
// the midpoint of their two loop neighbours (a loop whose order zig-zags at a sharp corner folds
// there); the domain's corners stay.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop {

struct UntangleResult {
  std::vector<Eigen::Vector2d> uv;  // #P, the untangled map (the input where nothing folded)
  std::size_t folded_before = 0;    // fold-overs found by check_map on the input
  std::size_t folded_after = 0;     // fold-overs left (0 on success): the fewest any round left,
                                    // whose map is uv (the input's when none did better)
  std::size_t moved = 0;            // points whose (u,v) changed
  int rounds = 0;                   // rounds used
};

// The nearest point of the edge of a map's domain (the disk's circle, the rectangle's sides), for
// untangle_map's to_edge; empty for another domain.
std::function<Eigen::Vector2d(const Eigen::Vector2d&)> domain_edge(const UVMap& map);

// P, N, nbrs, uv  as for check_map; outer_loop  the outer loop's point indices in order (may be
// empty); fixed  positions in outer_loop that never move (a rectangle's corners);
// to_edge  the nearest point of the domain's edge (empty: loop points never move).
// max_rounds >= 0: rounds of growing the region (0: only check). Nothing is moved when more than
// max_folded points fold (a map that bad needs another parameterisation, not a repair).
// Throws std::invalid_argument as check_map does, and for an outer_loop index out of range.
UntangleResult untangle_map(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                            const Neighborhoods& nbrs, const std::vector<Eigen::Vector2d>& uv,
                            const std::vector<int>& outer_loop, const std::vector<int>& fixed,
                            const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& to_edge,
                            int max_rounds, std::size_t max_folded);

}  // namespace scallop
