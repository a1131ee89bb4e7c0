#include "nodes/cloud/boundary.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nodes/geom/angular_gap.h"
#include "nodes/geom/tangent_frame.h"

namespace scallop {

bool angular_gap_exceeds(const std::vector<Eigen::Vector3d>& P, const Eigen::Vector3d& normal, std::size_t i,
                         const std::vector<int>& around, double angle) {
  Eigen::Vector3d t1, t2;
  tangent_frame(normal, t1, t2);
  thread_local std::vector<Eigen::Vector2d> d;
  d.clear();
  for (int j : around) {
    const Eigen::Vector3d e = P[j] - P[i];
    d.emplace_back(e.dot(t1), e.dot(t2));  // a duplicate or a point straight above: no direction
  }
  return angular_gap_exceeds(d.data(), d.size(), angle);
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
  tbb::enumerable_thread_specific<std::vector<std::size_t>> seen_by_thread;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<int> ring;
    std::vector<std::size_t>& seen = seen_by_thread.local();  // seen[q] == i + 1: q is in i's ring
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      ring.assign(nbrs.indices.begin() + i * nbrs.k, nbrs.indices.begin() + (i + 1) * nbrs.k);
      if (!angular_gap_exceeds(P, N[i], i, ring, angle)) continue;
      if (seen.empty()) seen.assign(n, 0);
      seen[i] = i + 1;
      for (int q : ring) seen[q] = i + 1;
      for (int j = 0; j < nbrs.k; ++j) {
        int q = nbrs.index(i, j);
        for (int m = 0; m < nbrs.k; ++m) {
          const int o = nbrs.index(q, m);
          if (seen[o] != i + 1) seen[o] = i + 1, ring.push_back(o);
        }
      }
      b[i] = angular_gap_exceeds(P, N[i], i, ring, angle) ? 1 : 0;
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
