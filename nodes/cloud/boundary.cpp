#include "nodes/cloud/boundary.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nodes/geom/tangent_frame.h"

namespace scallop {

double largest_angular_gap(const std::vector<Eigen::Vector3d>& P, const Eigen::Vector3d& normal,
                           std::size_t i, const std::vector<int>& around) {
  Eigen::Vector3d t1, t2;
  tangent_frame(normal, t1, t2);
  thread_local std::vector<double> a;
  a.clear();
  for (int j : around) {
    Eigen::Vector3d d = P[j] - P[i];
    double x = d.dot(t1), y = d.dot(t2);
    if (x == 0 && y == 0) continue;  // duplicate or straight above: no direction
    a.push_back(std::atan2(y, x));
  }
  if (a.empty()) return 2 * std::numbers::pi;
  std::sort(a.begin(), a.end());
  double gap = a.front() + 2 * std::numbers::pi - a.back();  // wrap-around gap
  for (std::size_t j = 1; j < a.size(); ++j) gap = std::max(gap, a[j] - a[j - 1]);
  return gap;
}

std::vector<std::uint8_t> detect_boundary(const std::vector<Eigen::Vector3d>& P,
                                          const std::vector<Eigen::Vector3d>& N,
                                          const Neighborhoods& nbrs, double angle, bool clean,
                                          const std::function<void(double)>& progress) {
  const std::size_t n = P.size();
  if (N.size() != n)
    throw std::invalid_argument("boundary detection needs normals (the cloud has " +
                                std::to_string(N.size()) + " normals for " + std::to_string(n) +
                                " points); run cloud.normals first");
  if (nbrs.size() != n)
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(nbrs.size()) +
                                " points but the cloud has " + std::to_string(n));
  if (nbrs.k < 3)
    throw std::invalid_argument("boundary detection needs k >= 3 neighbours per point (k = " +
                                std::to_string(nbrs.k) + ")");
  for (int idx : nbrs.indices)
    if (idx < 0 || static_cast<std::size_t>(idx) >= n)
      throw std::invalid_argument("a neighbour index is out of range");

  std::vector<std::uint8_t> b(n, 0);
  ParallelProgress done(progress, n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<int> ring;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      ring.assign(nbrs.indices.begin() + i * nbrs.k, nbrs.indices.begin() + (i + 1) * nbrs.k);
      if (largest_angular_gap(P, N[i], i, ring) <= angle) continue;
      for (int j = 0; j < nbrs.k; ++j) {
        int q = nbrs.index(i, j);
        for (int m = 0; m < nbrs.k; ++m) ring.push_back(nbrs.index(q, m));
      }
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      ring.erase(std::remove(ring.begin(), ring.end(), static_cast<int>(i)), ring.end());
      b[i] = largest_angular_gap(P, N[i], i, ring) > angle ? 1 : 0;
    }
    done.done(r.size());  // the cleaning pass below is quick
  });
  if (!clean) return b;

  std::vector<std::uint8_t> out(b);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (!b[i]) continue;
      int nb = 0;
      for (int j = 0; j < nbrs.k; ++j) nb += b[nbrs.index(i, j)];
      if (nb < 2) out[i] = 0;
    }
  });
  return out;
}

}  // namespace scallop
