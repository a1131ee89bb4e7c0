#include "nodes/cloud/clean.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "nodes/cloud/knn.h"
#include "nodes/cloud/stray_points.h"
#include "nodes/geom/spatial_order.h"

namespace scallop {

namespace {

PointCloud select(const PointCloud& in, const std::vector<std::size_t>& keep) {
  PointCloud out;
  out.points.reserve(keep.size());
  for (std::size_t i : keep) out.points.push_back(in.points[i]);
  if (in.has_normals()) {
    out.normals.reserve(keep.size());
    for (std::size_t i : keep) out.normals.push_back(in.normals[i]);
  }
  return out;
}

}  // namespace

PointCloud clean_cloud(const PointCloud& in, const CleanOptions& opts, CleanStats* stats) {
  CleanStats s;
  s.input = in.size();
  const bool normals = in.has_normals();

  // 1. Non-finite points.
  std::vector<std::size_t> keep;
  keep.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in.points[i].allFinite() && (!normals || in.normals[i].allFinite()))
      keep.push_back(i);
    else
      ++s.non_finite;
  }

  // 2. Exact duplicates: sort by (x, y, z, index); within a run of equal points all but the
  // first (lowest original index) go.
  {
    std::vector<std::size_t> order = keep;
    const auto& P = in.points;
    tbb::parallel_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const auto &p = P[a], &q = P[b];
      if (p.x() != q.x()) return p.x() < q.x();
      if (p.y() != q.y()) return p.y() < q.y();
      if (p.z() != q.z()) return p.z() < q.z();
      return a < b;
    });
    std::vector<char> dup(in.size(), 0);
    for (std::size_t r = 1; r < order.size(); ++r)
      if (P[order[r]] == P[order[r - 1]]) dup[order[r]] = 1;
    std::vector<std::size_t> unique;
    unique.reserve(keep.size());
    for (std::size_t i : keep) {
      if (dup[i])
        ++s.duplicates;
      else
        unique.push_back(i);
    }
    keep.swap(unique);
  }

  // 3. Statistical outliers.
  if (opts.remove_outliers && !keep.empty()) {
    const int k = opts.outlier_k;
    if (k < 1)
      throw std::invalid_argument("outlier removal needs outlier_k >= 1 (got " +
                                  std::to_string(k) + ")");
    if (keep.size() <= static_cast<std::size_t>(k))
      throw std::invalid_argument(
          "outlier removal with outlier_k = " + std::to_string(k) + " needs at least " +
          std::to_string(k + 1LL) + " points; the cloud has " + std::to_string(keep.size()) +
          " after removing " + std::to_string(s.non_finite) + " NaN/Inf and " +
          std::to_string(s.duplicates) + " duplicate points");
    std::vector<Eigen::Vector3d> P(keep.size());
    for (std::size_t r = 0; r < keep.size(); ++r) P[r] = in.points[keep[r]];
    const Neighborhoods nb = compute_knn(P, k);
    std::vector<double> mean_dist(P.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        double sum = 0;
        for (int j = 0; j < k; ++j) sum += std::sqrt(nb.sq_dist(i, j));
        mean_dist[i] = sum / k;
      }
    });
    const double n = static_cast<double>(P.size());
    const double mu = std::accumulate(mean_dist.begin(), mean_dist.end(), 0.0) / n;
    double var = 0;
    for (double d : mean_dist) var += (d - mu) * (d - mu);
    var = P.size() > 1 ? var / (n - 1) : 0.0;
    const double limit = mu + opts.outlier_std_ratio * std::sqrt(var);
    std::vector<std::size_t> inliers;
    inliers.reserve(keep.size());
    for (std::size_t r = 0; r < keep.size(); ++r) {
      if (mean_dist[r] > limit)
        ++s.outliers;
      else
        inliers.push_back(keep[r]);
    }
    keep.swap(inliers);
  }

  // 4. Stray points.
  if (opts.remove_stray && !keep.empty()) {
    const int k = opts.stray_k;
    if (k < 8) throw std::invalid_argument("stray point removal needs stray_k >= 8 (got " + std::to_string(k) + ")");
    if (keep.size() <= static_cast<std::size_t>(k))
      throw std::invalid_argument("stray point removal with stray_k = " + std::to_string(k) + " needs at least " +
                                  std::to_string(k + 1LL) + " points; the cloud has " + std::to_string(keep.size()) +
                                  " after the steps before it");
    // Again on the points left while some were dropped, up to 3 rounds: stray points near one
    // another (a burst of them in the air) are each other's neighbours until most are gone
    // (0.5 % stray points on the catalog's dome: 236 of 250 in the first round, the rest in the
    // second).
    for (int round = 0; round < 3 && keep.size() > static_cast<std::size_t>(k); ++round) {
      std::vector<Eigen::Vector3d> P(keep.size());
      for (std::size_t r = 0; r < keep.size(); ++r) P[r] = in.points[keep[r]];
      const std::vector<std::uint8_t> stray = stray_points(P, compute_knn(P, k));
      std::vector<std::size_t> on_surface;
      on_surface.reserve(keep.size());
      for (std::size_t r = 0; r < keep.size(); ++r)
        if (!stray[r]) on_surface.push_back(keep[r]);
      if (on_surface.size() == keep.size()) break;
      s.stray += keep.size() - on_surface.size();
      keep.swap(on_surface);
    }
  }

  s.output = keep.size();
  if (stats) *stats = s;
  if (opts.spatial_order) {
    std::vector<Eigen::Vector3d> kept(keep.size());
    for (std::size_t r = 0; r < keep.size(); ++r) kept[r] = in.points[keep[r]];
    std::vector<std::size_t> along;
    for (std::size_t r : scallop::spatial_order(kept)) along.push_back(keep[r]);
    keep.swap(along);
  }
  return select(in, keep);
}

}  // namespace scallop
