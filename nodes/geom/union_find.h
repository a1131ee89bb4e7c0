// Disjoint sets of the indices 0 .. n-1, for joining faces, corners or vertices into groups.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace scallop {

// Each set's root is its smallest index (join hangs the larger root under the smaller), so that
// the groups come out the same whatever order they were joined in.
class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::uint32_t{0}); }
  std::uint32_t root(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];  // path halving
    return x;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = root(a), b = root(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace scallop
