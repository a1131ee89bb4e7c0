// Indices filed by the cube of a uniform 3-D grid they fall in, the cubes hashed: for "what lies
// near this place" where a k-d tree is not worth building (entries added one by one, or filed in
// several cells).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace scallop {

class CellHash3 {
 public:
  using Key = std::array<std::int64_t, 3>;
  // cell  the cubes' side (mm), > 0
  explicit CellHash3(double cell) : cell_(cell) {}
  double cell() const { return cell_; }
  // the cube p lies in
  Key key(const Eigen::Vector3d& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / cell_)), static_cast<std::int64_t>(std::floor(p.y() / cell_)),
            static_cast<std::int64_t>(std::floor(p.z() / cell_))};
  }
  // the cubes' hash (a map keyed by Key may use it as its hasher)
  static std::uint64_t hash(const Key& k) {
    return static_cast<std::uint64_t>(k[0]) * 73856093ULL ^ static_cast<std::uint64_t>(k[1]) * 19349663ULL ^
           static_cast<std::uint64_t>(k[2]) * 83492791ULL;
  }
  void add(const Key& k, std::size_t index) { cells_[hash(k)].push_back(index); }
  void add(const Eigen::Vector3d& p, std::size_t index) { add(key(p), index); }
  // f(index) for every index filed in the cubes within `rings` cubes of p's along each axis (so
  // every one filed at a place within rings × cell of p; some more, as a hash collision adds
  // candidates, and an index filed in several of them more than once), cube by cube in x, y, z order.
  template <class F>
  void near(const Eigen::Vector3d& p, int rings, F&& f) const {
    const Key c = key(p);
    for (int i = -rings; i <= rings; ++i)
      for (int j = -rings; j <= rings; ++j)
        for (int l = -rings; l <= rings; ++l)
          if (const auto it = cells_.find(hash({c[0] + i, c[1] + j, c[2] + l})); it != cells_.end())
            for (std::size_t index : it->second) f(index);
  }

 private:
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;  // a hash collision only adds candidates
};

}  // namespace scallop
