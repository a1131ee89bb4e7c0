// Where a sampled maximum is refined: the seeds of the local grids that post.simulate and
// post.simulate_part trace around their highest samples.
//
// The highest `count` values alone (verify.py's rule) can be crowded out: many samples along
// cusps a little higher than the grid happened to catch of a sharp, isolated peak fill them all,
// and the peak is never refined (a planar-map raster's corner on the freeform patch, stop 94:
// the judge found 0.0516 mm there, a certificate seeded from its top 1000 only 0.0504). So the
// highest sample of every cubic cell that reaches `share` of the highest value is a seed too.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

namespace scallop {

// The simulations' first refinement level seeds from each cell of kSeedCell grid spacings whose
// highest value reaches kSeedShare of the highest: about one seed per 1 000 grid samples, some
// 15 % more traces than the grid's own.
constexpr double kSeedCell = 32;
constexpr double kSeedShare = 0.75;

// value  #S, a sample's value; one that is not > 0 (or NaN) is never a seed.
// Returns the indices of the `count` highest values, in no order.
std::vector<std::size_t> highest_values(const std::vector<double>& value, std::size_t count);

// value  #S as above; position  #S by 3 (mm); cell > 0 (mm); share in [0, 1].
// Returns, for every cubic cell of side `cell` (cells of the lattice through the origin), the
// index of its highest sample when that value is at least share × the highest of all; ascending.
std::vector<std::size_t> highest_per_cell(const std::vector<double>& value,
                                          const std::vector<Eigen::Vector3d>& position, double cell, double share);
// The same with each sample's position asked of position_of(i) (the simulations' samples hold
// their own: no copy of a grid of millions).
std::vector<std::size_t> highest_per_cell_at(const std::vector<double>& value,
                                             const std::function<Eigen::Vector3d(std::size_t)>& position_of,
                                             double cell, double share);

}  // namespace scallop
