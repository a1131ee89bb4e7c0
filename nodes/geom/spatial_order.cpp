#include "nodes/geom/spatial_order.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdint>
#include <utility>

namespace scallop {

namespace {

// The 21 low bits of v spread to every third bit (bit b to bit 3 b).
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

}  // namespace

std::vector<std::size_t> spatial_order(const std::vector<Eigen::Vector3d>& P) {
  const std::size_t n = P.size();
  std::vector<std::size_t> order(n);
  if (n == 0) return order;
  Eigen::Vector3d lo = P[0], hi = P[0];
  for (const auto& p : P) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double extent = (hi - lo).maxCoeff();
  const double scale = extent > 0 ? ((1 << 21) - 1) / extent : 0.0;  // one scale: cubic cells
  std::vector<std::pair<std::uint64_t, std::size_t>> key(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d c = (P[i] - lo) * scale;
    key[i] = {spread_bits(static_cast<std::uint64_t>(c.x())) | spread_bits(static_cast<std::uint64_t>(c.y())) << 1 |
                  spread_bits(static_cast<std::uint64_t>(c.z())) << 2,
              i};
  }
  tbb::parallel_sort(key.begin(), key.end());
  for (std::size_t i = 0; i < n; ++i) order[i] = key[i].second;
  return order;
}

}  // namespace scallop
