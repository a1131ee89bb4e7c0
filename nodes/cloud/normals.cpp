#include "nodes/cloud/normals.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace scallop {

namespace {

void check_neighborhoods(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nbrs) {
  if (P.empty()) throw std::invalid_argument("the cloud is empty");
  if (nbrs.k < 2)
    throw std::invalid_argument("normals need at least 2 neighbours per point (k = " +
                                std::to_string(nbrs.k) + ")");
  if (nbrs.indices.size() != P.size() * nbrs.k || nbrs.sq_dists.size() != nbrs.indices.size())
    throw std::invalid_argument("the neighbourhoods are for " + std::to_string(nbrs.size()) +
                                " points but the cloud has " + std::to_string(P.size()));
  const int n = static_cast<int>(P.size());
  for (std::size_t e = 0; e < nbrs.indices.size(); ++e)
    if (nbrs.indices[e] < 0 || nbrs.indices[e] >= n)
      throw std::invalid_argument("neighbour index " + std::to_string(nbrs.indices[e]) +
                                  " of point " + std::to_string(e / nbrs.k) +
                                  " is outside the cloud of " + std::to_string(n) + " points");
}

}  // namespace

NormalOrientation parse_normal_orientation(const std::string& name) {
  if (name == "up") return NormalOrientation::Up;
  if (name == "mst") return NormalOrientation::Mst;
  if (name == "auto") return NormalOrientation::Auto;
  throw std::invalid_argument("unknown normal orientation '" + name +
                              "' (expected up, mst or auto)");
}

std::vector<Eigen::Vector3d> pca_normals(const std::vector<Eigen::Vector3d>& P,
                                         const Neighborhoods& nbrs,
                                         std::vector<double>* surface_variation) {
  check_neighborhoods(P, nbrs);
  const std::size_t n = P.size();
  const int k = nbrs.k;
  std::vector<Eigen::Vector3d> N(n);
  if (surface_variation) surface_variation->assign(n, 0.0);
  std::atomic<std::size_t> first_bad{n};

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      // Coordinates relative to the point itself keep the sums well-conditioned far from the
      // origin (a part placed at x = 500 mm).
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int j = 0; j < k; ++j) mean += P[nbrs.index(i, j)] - P[i];
      mean /= (k + 1);
      Eigen::Matrix3d C = mean * mean.transpose();  // the point itself, at 0
      for (int j = 0; j < k; ++j) {
        const Eigen::Vector3d d = P[nbrs.index(i, j)] - P[i] - mean;
        C += d * d.transpose();
      }
      C /= (k + 1);
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);  // eigenvalues ascending
      const Eigen::Vector3d lambda = es.eigenvalues().cwiseMax(0.0);
      if (!(lambda[1] > 1e-12 * lambda[2])) {  // also catches lambda2 == 0 and NaN
        std::size_t cur = first_bad.load();
        while (i < cur && !first_bad.compare_exchange_weak(cur, i)) {
        }
        continue;
      }
      N[i] = es.eigenvectors().col(0).normalized();
      if (surface_variation) (*surface_variation)[i] = lambda[0] / lambda.sum();
    }
  });

  if (const std::size_t i = first_bad.load(); i < n) {
    std::ostringstream msg;
    msg << "the neighbourhood of point " << i << " at (" << P[i].x() << ", " << P[i].y() << ", "
        << P[i].z() << ") mm is degenerate: the point and its " << k
        << " neighbours are coincident or collinear, so its normal is undefined; remove "
           "duplicate points (cloud.clean) or use a larger k";
    throw std::invalid_argument(msg.str());
  }
  return N;
}

void orient_normals_up(std::vector<Eigen::Vector3d>& N) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      if (N[i].z() < 0) N[i] = -N[i];
  });
}

void orient_normals_mst(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nbrs,
                        std::vector<Eigen::Vector3d>& N) {
  check_neighborhoods(P, nbrs);
  if (N.size() != P.size())
    throw std::invalid_argument("there are " + std::to_string(N.size()) + " normals for " +
                                std::to_string(P.size()) + " points");
  const int n = static_cast<int>(P.size());
  const int k = nbrs.k;

  // Symmetrised KNN graph in compressed rows: j in knn(i) gives edges i-j and j-i. An edge
  // listed twice (mutual neighbours) is harmless for Prim.
  std::vector<int> start(n + 1, 0);
  for (int i = 0; i < n; ++i) {
    start[i + 1] += k;
    for (int j = 0; j < k; ++j) start[nbrs.index(i, j) + 1] += 1;
  }
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> adj(start[n]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < k; ++j) {
      const int m = nbrs.index(i, j);
      adj[fill[i]++] = m;
      adj[fill[m]++] = i;
    }

  // Seeds in order of decreasing z (ties: lower index first); each unvisited one starts a
  // component.
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return P[a].z() > P[b].z() || (P[a].z() == P[b].z() && a < b);
  });

  std::vector<char> done(n, 0);
  // Lazy Prim: an entry is pushed only when it improves the best known edge to its node, which
  // keeps the heap several times smaller than pushing every edge; stale entries are skipped.
  std::vector<double> best(n, std::numeric_limits<double>::infinity());
  // (weight, node, parent): full tuple order keeps the traversal deterministic.
  using Item = std::tuple<double, int, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (int seed : order) {
    if (done[seed]) continue;
    if (N[seed].z() < 0) N[seed] = -N[seed];
    heap.emplace(0.0, seed, -1);
    while (!heap.empty()) {
      const auto [w, v, parent] = heap.top();
      heap.pop();
      if (done[v]) continue;
      done[v] = 1;
      if (parent >= 0 && N[v].dot(N[parent]) < 0) N[v] = -N[v];
      for (int e = start[v]; e < start[v + 1]; ++e) {
        const int u = adj[e];
        if (done[u]) continue;
        const double wu = 1.0 - std::abs(N[v].dot(N[u]));
        if (wu < best[u]) {
          best[u] = wu;
          heap.emplace(wu, u, v);
        }
      }
    }
  }
}

std::vector<Eigen::Vector3d> estimate_normals(const std::vector<Eigen::Vector3d>& P,
                                              const Neighborhoods& nbrs, NormalOrientation mode,
                                              std::vector<double>* surface_variation) {
  std::vector<Eigen::Vector3d> N = pca_normals(P, nbrs, surface_variation);
  if (mode == NormalOrientation::Up) {
    orient_normals_up(N);
    return N;
  }
  orient_normals_mst(P, nbrs, N);
  if (mode == NormalOrientation::Auto) {
    std::size_t up = 0, down = 0;
    for (const auto& v : N) {
      up += v.z() > 0;
      down += v.z() < 0;
    }
    if (down > up)
      for (auto& v : N) v = -v;
  }
  return N;
}

}  // namespace scallop
