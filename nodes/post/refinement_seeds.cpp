#include "nodes/post/refinement_seeds.h"

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
  if (!(cell > 0) || !(share >= 0 && share <= 1))
    throw std::invalid_argument("highest_per_cell: cell must be > 0 and share in [0, 1]");
  double top = 0;
  for (double v : value)
    if (v > top) top = v;
  if (!(top > 0)) return {};
  const double floor = share * top;
  struct Key {
    std::int64_t x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      return std::size_t(k.x * 73856093) ^ std::size_t(k.y * 19349663) ^ std::size_t(k.z * 83492791);
    }
  };
  std::unordered_map<Key, std::size_t, Hash> best;
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (!(value[i] > 0) || value[i] < floor) continue;
    const Eigen::Vector3d& p = position[i];
    if (!p.allFinite()) continue;
    const Key k{std::int64_t(std::floor(p.x() / cell)), std::int64_t(std::floor(p.y() / cell)),
                std::int64_t(std::floor(p.z() / cell))};
    auto [it, inserted] = best.try_emplace(k, i);
    if (!inserted && value[i] > value[it->second]) it->second = i;
  }
  std::vector<std::size_t> seeds;
  seeds.reserve(best.size());
  for (const auto& kv : best) seeds.push_back(kv.second);
  std::sort(seeds.begin(), seeds.end());
  return seeds;
}

}  // namespace scallop
