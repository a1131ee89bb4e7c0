#include "nodes/post/refinement_seeds.h"

#include "nodes/geom/cell_hash_3d.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace scallop {

std::vector<std::size_t> highest_values(const std::vector<double>& value, std::size_t count) {
  std::vector<std::size_t> c;
  for (std::size_t i = 0; i < value.size(); ++i)
    if (value[i] > 0) c.push_back(i);
  if (c.size() > count) {
    std::nth_element(c.begin(), c.begin() + std::ptrdiff_t(count), c.end(),
                     [&](std::size_t a, std::size_t b) { return value[a] > value[b]; });
    c.resize(count);
  }
  return c;
}

std::vector<std::size_t> highest_per_cell(const std::vector<double>& value,
                                          const std::vector<Eigen::Vector3d>& position, double cell, double share) {
  if (value.size() != position.size()) throw std::invalid_argument("highest_per_cell: one position per value");
  return highest_per_cell_at(value, [&position](std::size_t i) { return position[i]; }, cell, share);
}

std::vector<std::size_t> highest_per_cell_at(const std::vector<double>& value,
                                             const std::function<Eigen::Vector3d(std::size_t)>& position_of,
                                             double cell, double share) {
  if (!(cell > 0) || !(share >= 0 && share <= 1))
    throw std::invalid_argument("highest_per_cell: cell must be > 0 and share in [0, 1]");
  double top = 0;
  for (double v : value)
    if (v > top) top = v;
  if (!(top > 0)) return {};
  const double floor = share * top;
  const CellHash3 cubes(cell);
  struct Hash {
    std::size_t operator()(const CellHash3::Key& k) const { return std::size_t(CellHash3::hash(k)); }
  };
  std::unordered_map<CellHash3::Key, std::size_t, Hash> best;  // cube -> its highest sample
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (!(value[i] > 0) || value[i] < floor) continue;
    const Eigen::Vector3d p = position_of(i);
    if (!p.allFinite()) continue;
    auto [it, inserted] = best.try_emplace(cubes.key(p), i);
    if (!inserted && value[i] > value[it->second]) it->second = i;
  }
  std::vector<std::size_t> seeds;
  seeds.reserve(best.size());
  for (const auto& kv : best) seeds.push_back(kv.second);
  std::sort(seeds.begin(), seeds.end());
  return seeds;
}

}  // namespace scallop
