#include "nodes/param/untangle.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "nodes/param/check.h"

namespace scallop {

std::function<Eigen::Vector2d(const Eigen::Vector2d&)> domain_edge(const UVMap& map) {
  if (map.domain == "disk") {
    const double R = map.radius;
    return [R](const Eigen::Vector2d& q) {
      const double n = q.norm();
      return n > 0 ? Eigen::Vector2d(q * (R / n)) : Eigen::Vector2d(R, 0);
    };
  }
  if (map.domain == "rectangle") {
    const double W = map.width, H = map.height;
    return [W, H](const Eigen::Vector2d& q) {
      Eigen::Vector2d p(std::clamp(q.x(), 0.0, W), std::clamp(q.y(), 0.0, H));
      const double d[4] = {p.x(), W - p.x(), p.y(), H - p.y()};  // to each side
      switch (std::min_element(d, d + 4) - d) {
        case 0: p.x() = 0; break;
        case 1: p.x() = W; break;
        case 2: p.y() = 0; break;
        default: p.y() = H;
      }
      return p;
    };
  }
  return {};
}

UntangleResult untangle_map(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                            const Neighborhoods& nbrs, const std::vector<Eigen::Vector2d>& uv,
                            const std::vector<int>& outer_loop, const std::vector<int>& fixed,
                            const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& to_edge,
                            int max_rounds, std::size_t max_folded) {
  UntangleResult res;
  res.uv = uv;
  MapCheck c = check_map(P, N, nbrs, res.uv);
  res.folded_before = res.folded_after = c.foldovers;
  if (c.foldovers == 0 || c.foldovers > max_folded) return res;

  const std::size_t n = P.size();
  // loop_pos[i]: position of point i in the outer loop, -1 off it
  std::vector<int> loop_pos(n, -1);
  for (std::size_t k = 0; k < outer_loop.size(); ++k) {
    const int i = outer_loop[k];
    if (i < 0 || static_cast<std::size_t>(i) >= n)
      throw std::invalid_argument("an outer loop index (" + std::to_string(i) + ") is outside the cloud");
    loop_pos[i] = static_cast<int>(k);
  }
  std::vector<char> pinned(n, 0);
  for (int k : fixed)
    if (k >= 0 && static_cast<std::size_t>(k) < outer_loop.size()) pinned[outer_loop[k]] = 1;
  const int L = static_cast<int>(outer_loop.size());
  std::vector<char> region(n, 0);
  for (std::size_t i = 0; i < n; ++i) region[i] = c.folded[i];
  // The rounds relax a growing region, which can fold more points than it unfolds (a scanned
  // bunny cut at 65 degrees: 8 fold-overs, 29 after ten rounds): the map with the fewest is kept.
  std::vector<Eigen::Vector2d> best = res.uv;
  for (int round = 1; round <= max_rounds && c.foldovers > 0; ++round) {
    // Grow the region by one ring of neighbours around every point still folded (and keep what
    // earlier rounds took), then relax it: Gauss-Seidel sweeps of uv_i = mean of its neighbours.
    std::vector<char> grown = region;
    for (std::size_t i = 0; i < n; ++i)
      if (c.folded[i] || region[i])
        for (int j = 0; j < nbrs.k; ++j) grown[nbrs.index(i, j)] = 1;
    region.swap(grown);
    for (int sweep = 0; sweep < 20 * round; ++sweep)
      for (std::size_t i = 0; i < n; ++i) {
        if (!region[i] || pinned[i]) continue;
        if (loop_pos[i] >= 0) {
          if (!to_edge || L < 3) continue;
          const int k = loop_pos[i];
          res.uv[i] = to_edge(0.5 * (res.uv[outer_loop[(k + L - 1) % L]] + res.uv[outer_loop[(k + 1) % L]]));
          continue;
        }
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (int j = 0; j < nbrs.k; ++j) mean += res.uv[nbrs.index(i, j)];
        res.uv[i] = mean / nbrs.k;
      }
    c = check_map(P, N, nbrs, res.uv);
    res.rounds = round;
    if (c.foldovers < res.folded_after) res.folded_after = c.foldovers, best = res.uv;
  }
  res.uv.swap(best);
  for (std::size_t i = 0; i < n; ++i) res.moved += res.uv[i] != uv[i];
  return res;
}

}  // namespace scallop
