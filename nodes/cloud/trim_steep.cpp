#include "nodes/cloud/trim_steep.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nodes/cloud/knn.h"
#include "nodes/cloud/principal_extents.h"
#include "nodes/cloud/normals.h"
#include "nodes/geom/union_find.h"

namespace scallop {

namespace {

// Components of the symmetric k-nearest-neighbour graph restricted to the points with mask[i].
// With `through_masked_only`, a point is joined only to its neighbours nearer than its nearest
// unmasked one: two pieces with unmasked points between them stay apart (a row of gentle points
// that the trim left beyond a steep band is not joined over the band to the surface behind it).
// Returns the label of every masked point (-1 elsewhere), numbered in order of each component's
// smallest index. Joined in a union-find rather than walked over adjacency lists: a million
// points' lists cost more in allocation than the whole walk.
std::vector<int> masked_components(const Neighborhoods& nbrs, const std::vector<char>& mask, int& count,
                                   bool through_masked_only = false) {
  const std::size_t n = nbrs.size();
  UnionFind sets(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i]) continue;
    for (int j = 0; j < nbrs.k; ++j) {
      const int o = nbrs.index(i, j);
      if (o >= 0 && !mask[o] && through_masked_only) break;
      if (o >= 0 && mask[o]) sets.join(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(o));
    }
  }
  // A set's root is its smallest index, so the first masked index of each set is its root.
  std::vector<int> label(n, -1);
  count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i]) continue;
    const std::uint32_t r = sets.root(static_cast<std::uint32_t>(i));
    label[i] = r == i ? count++ : label[r];
  }
  return label;
}

}  // namespace

TrimSteepResult trim_steep(const std::vector<Eigen::Vector3d>& P, const TrimSteepOptions& o) {
  if (!(o.max_slope_deg > 0 && o.max_slope_deg <= 90))
    throw std::invalid_argument("max_slope must be in (0, 90] degrees (got " +
                                std::to_string(o.max_slope_deg) + ")");
  if (o.k < 3) throw std::invalid_argument("k must be at least 3 (got " + std::to_string(o.k) + ")");
  if (P.size() <= static_cast<std::size_t>(o.k))
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; trimming needs more than k = " + std::to_string(o.k));
  Neighborhoods nbrs = compute_knn(P, o.k);
  // A line's normals tilt any way around it: it would be "trimmed as steep", not named.
  if (auto line = one_dimensional_problem(principal_extents(P), median_spacing(nbrs)); !line.empty())
    throw std::invalid_argument(line);
  const std::vector<Eigen::Vector3d> N = pca_normals(P, nbrs);
  const std::size_t n = P.size();
  std::vector<double> slope(n), area(n);
  std::vector<char> gentle(n);
  TrimSteepResult r;
  for (std::size_t i = 0; i < n; ++i) {
    slope[i] = std::acos(std::min(1.0, std::abs(N[i].z()))) * 180 / std::numbers::pi;
    area[i] = std::numbers::pi * nbrs.sq_dist(i, nbrs.k - 1) / (nbrs.k + 1);
    gentle[i] = slope[i] <= o.max_slope_deg;
    r.area += area[i];
    if (!gentle[i]) ++r.steep;
  }
  // The largest gentle piece is kept.
  int count = 0;
  const std::vector<int> piece = masked_components(nbrs, gentle, count, /*through_masked_only=*/true);
  std::vector<std::size_t> size(count, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (piece[i] >= 0) ++size[piece[i]];
  const int largest = count ? static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin()) : -1;
  std::vector<char> dropped(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (piece[i] == largest && largest >= 0) {
      r.kept.push_back(i);
      r.max_slope_kept_deg = std::max(r.max_slope_kept_deg, slope[i]);
    } else {
      dropped[i] = 1;
      r.trimmed_area += area[i];
      if (gentle[i]) ++r.cut_off;
    }
  }
  // Where the points not kept lie: their connected pieces, largest area first.
  int dcount = 0;
  const std::vector<int> dpiece = masked_components(nbrs, dropped, dcount);
  std::vector<TrimmedRegion> regions(dcount);
  for (auto& g : regions) {
    g.min = Eigen::Vector3d::Constant(INFINITY);
    g.max = -g.min;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (dpiece[i] < 0) continue;
    TrimmedRegion& g = regions[dpiece[i]];
    ++g.points;
    g.area += area[i];
    g.centroid += P[i];
    g.min = g.min.cwiseMin(P[i]);
    g.max = g.max.cwiseMax(P[i]);
    g.max_slope_deg = std::max(g.max_slope_deg, slope[i]);
  }
  for (auto& g : regions) g.centroid /= static_cast<double>(g.points);
  std::sort(regions.begin(), regions.end(),
            [](const TrimmedRegion& a, const TrimmedRegion& b) { return a.area > b.area; });
  if (regions.size() > 10) regions.resize(10);
  r.regions = std::move(regions);
  if (r.kept.size() == n) {
    r.neighbors = std::move(nbrs);
  } else if (r.kept.size() > static_cast<std::size_t>(o.k)) {
    std::vector<Eigen::Vector3d> kept(r.kept.size());
    for (std::size_t j = 0; j < kept.size(); ++j) kept[j] = P[r.kept[j]];
    r.neighbors = compute_knn(kept, o.k);
  }
  return r;
}

}  // namespace scallop
