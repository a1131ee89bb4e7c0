#include "nodes/cloud/knn.h"

#include <gtest/gtest.h>

#include "tests/test_support.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "engine/node.h"

namespace scallop {
namespace {

// Squared distance summed in x, y, z order, as the k-d tree's metric does, so that equal
// distances compare equal bit for bit.
double sq(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return dx * dx + dy * dy + dz * dz;
}

Neighborhoods brute_force(const std::vector<Eigen::Vector3d>& P, int k) {
  Neighborhoods out;
  out.k = k;
  for (std::size_t i = 0; i < P.size(); ++i) {
    std::vector<std::pair<double, int>> c;
    for (std::size_t j = 0; j < P.size(); ++j)
      if (j != i) c.emplace_back(sq(P[i], P[j]), static_cast<int>(j));
    std::partial_sort(c.begin(), c.begin() + k, c.end());  // (distance, index) order
    for (int j = 0; j < k; ++j) {
      out.indices.push_back(c[j].second);
      out.sq_dists.push_back(c[j].first);
    }
  }
  return out;
}

void expect_same(const Neighborhoods& a, const Neighborhoods& b) {
  ASSERT_EQ(a.k, b.k);
  ASSERT_EQ(a.indices.size(), b.indices.size());
  for (std::size_t e = 0; e < a.indices.size(); ++e) {
    ASSERT_EQ(a.indices[e], b.indices[e]) << "point " << e / a.k << " neighbour " << e % a.k;
    ASSERT_EQ(a.sq_dists[e], b.sq_dists[e]) << "point " << e / a.k << " neighbour " << e % a.k;
  }
}

std::vector<Eigen::Vector3d> random_cloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<Eigen::Vector3d> P(n);
  for (auto& p : P) p = {u(rng), u(rng), 0.1 * u(rng)};
  return P;
}

TEST(Knn, EqualsBruteForceOnRandomClouds) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto P = random_cloud(700, seed);
    for (int k : {1, 5, 12, 40}) expect_same(compute_knn(P, k), brute_force(P, k));
  }
}

TEST(Knn, EqualsBruteForceWithDuplicates) {
  auto P = random_cloud(400, 7);
  // Exact copies, some several times, scattered through the index range.
  std::mt19937 rng(11);
  for (int c = 0; c < 150; ++c) {
    const std::size_t from = rng() % 400;
    P.insert(P.begin() + static_cast<long>(rng() % P.size()), P[from]);
  }
  for (int k : {1, 3, 12}) expect_same(compute_knn(P, k), brute_force(P, k));
}

TEST(Knn, TiesOnAGridAreOrderedByIndex) {
  // An integer grid has many neighbours at exactly equal distances.
  std::vector<Eigen::Vector3d> P;
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 9; ++y)
      for (int z = 0; z < 3; ++z) P.emplace_back(x, y, z);
  std::shuffle(P.begin(), P.end(), std::mt19937(5));
  for (int k : {4, 6, 18, 26}) expect_same(compute_knn(P, k), brute_force(P, k));
}

TEST(Knn, ManyNeighboursAsTheDenoiserAsks) {
  // k in the hundreds: the k best are kept in a heap and put in order at the end.
  expect_same(compute_knn(random_cloud(900, 4), 300), brute_force(random_cloud(900, 4), 300));
  std::vector<Eigen::Vector3d> grid;
  for (int x = 0; x < 14; ++x)
    for (int y = 0; y < 14; ++y)
      for (int z = 0; z < 4; ++z) grid.emplace_back(x, y, z);
  std::shuffle(grid.begin(), grid.end(), std::mt19937(6));
  for (int k : {100, 257}) expect_same(compute_knn(grid, k), brute_force(grid, k));
}

TEST(Knn, ADuplicateIsItsTwinsNearestNeighbour) {
  std::vector<Eigen::Vector3d> P = {{0, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, 2, 0}};
  const Neighborhoods nb = compute_knn(P, 2);
  EXPECT_EQ(nb.index(0, 0), 2);
  EXPECT_EQ(nb.sq_dist(0, 0), 0.0);
  EXPECT_EQ(nb.index(2, 0), 0);
  EXPECT_EQ(nb.index(2, 1), 1);
  EXPECT_EQ(nb.sq_dist(2, 1), 1.0);
}

TEST(Knn, LayoutAndSize) {
  const auto P = random_cloud(100, 3);
  const Neighborhoods nb = compute_knn(P, 7);
  EXPECT_EQ(nb.k, 7);
  EXPECT_EQ(nb.size(), 100u);
  EXPECT_EQ(nb.indices.size(), 700u);
  for (std::size_t i = 0; i < nb.size(); ++i)
    for (int j = 1; j < 7; ++j) EXPECT_LE(nb.sq_dist(i, j - 1), nb.sq_dist(i, j));
}

void expect_invalid(const std::vector<Eigen::Vector3d>& P, int k, const std::string& text) {
  try {
    compute_knn(P, k);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), text);
  }
}

TEST(Knn, ErrorTexts) {
  const auto P = random_cloud(5, 1);
  expect_invalid(P, 12, "k = 12 needs at least 13 points; the cloud has 5");
  expect_invalid(P, 5, "k = 5 needs at least 6 points; the cloud has 5");
  expect_invalid({}, 1, "k = 1 needs at least 2 points; the cloud has 0");
  expect_invalid(P, 0, "k must be at least 1 (got 0)");
  auto bad = random_cloud(20, 1);
  bad[13].y() = std::numeric_limits<double>::quiet_NaN();
  expect_invalid(bad, 3, "point 13 has a NaN or infinite coordinate");
  bad[13].y() = 0;
  bad[4].z() = -std::numeric_limits<double>::infinity();
  expect_invalid(bad, 3, "point 4 has a NaN or infinite coordinate");
}

TEST(KnnIndex, QueriesEqualBruteForce) {
  const auto P = random_cloud(500, 9);
  const KnnIndex index(P);
  EXPECT_EQ(index.size(), 500u);
  const auto Q = random_cloud(50, 10);
  std::vector<int> idx;
  std::vector<double> d;
  for (const auto& q : Q) {
    std::vector<std::pair<double, int>> c;
    for (std::size_t j = 0; j < P.size(); ++j) c.emplace_back(sq(q, P[j]), static_cast<int>(j));
    std::sort(c.begin(), c.end());
    index.query(q, 8, idx, d);
    ASSERT_EQ(idx.size(), 8u);
    for (int j = 0; j < 8; ++j) {
      EXPECT_EQ(idx[j], c[j].second);
      EXPECT_EQ(d[j], c[j].first);
    }
    EXPECT_EQ(index.nearest(q), c[0].second);
  }
  // Querying at a point of P with skip leaves that point out; k beyond #P is clamped.
  index.query(P[17], 3, idx, d, 17);
  EXPECT_EQ(idx.size(), 3u);
  EXPECT_TRUE(std::find(idx.begin(), idx.end(), 17) == idx.end());
  index.query(P[17], 1000, idx, d, 17);
  EXPECT_EQ(idx.size(), 499u);
  index.query(P[17], 1000, idx, d);
  EXPECT_EQ(idx.size(), 500u);
  EXPECT_EQ(idx[0], 17);
}

TEST(KnnIndex, TheKthDistanceAndTheSearchWithinItGiveWhatTheQueryGives) {
  // On random points and on a grid, where many distances tie at the k-th: query_within must then
  // keep the lowest indices, as query does.
  std::vector<Eigen::Vector3d> grid;
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y)
      for (int z = 0; z < 3; ++z) grid.emplace_back(x, y, z);
  std::shuffle(grid.begin(), grid.end(), std::mt19937(8));
  for (const auto& P : {random_cloud(600, 12), grid}) {
    const KnnIndex index(P);
    std::vector<int> idx, idx_within;
    std::vector<double> d, d_within;
    for (int i = 0; i < static_cast<int>(P.size()); i += 7)
      for (int k : {1, 6, 40, 250}) {
        index.query(P[i], k, idx, d, i);
        const double kth = index.kth_sq_distance(P[i], k, i);
        ASSERT_EQ(kth, d.back()) << "point " << i << ", k = " << k;
        // a guess too small (fewer than k within it), exact (ties at it) or wide: the same
        for (double guess : {0.5 * kth, kth, 2 * kth + 1})
          ASSERT_EQ(index.kth_sq_distance(P[i], k, i, guess), kth) << "point " << i << ", k = " << k << ", guess " << guess;
        index.query_within(P[i], kth, k, idx_within, d_within, i);
        ASSERT_EQ(idx_within, idx) << "point " << i << ", k = " << k;
        ASSERT_EQ(d_within, d) << "point " << i << ", k = " << k;
        // out of order: the same points, each with its distance
        index.query_within(P[i], kth, k, idx_within, d_within, i, false);
        std::vector<std::pair<int, double>> unordered, ordered;
        for (std::size_t j = 0; j < idx.size(); ++j) ordered.emplace_back(idx[j], d[j]);
        for (std::size_t j = 0; j < idx_within.size(); ++j) unordered.emplace_back(idx_within[j], d_within[j]);
        std::sort(ordered.begin(), ordered.end());
        std::sort(unordered.begin(), unordered.end());
        ASSERT_EQ(unordered, ordered) << "point " << i << ", k = " << k;
      }
    // Fewer points than k: every one, the farthest last.
    index.query(P[0], 5000, idx, d, 0);
    EXPECT_EQ(idx.size(), P.size() - 1);
    EXPECT_EQ(index.kth_sq_distance(P[0], 5000, 0), d.back());
    EXPECT_EQ(index.kth_sq_distance(P[0], 5000, 0, 1e9), d.back());
  }
}

TEST(KnnIndex, EmptyCloudIsAnError) {
  try {
    KnnIndex index(std::vector<Eigen::Vector3d>{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "the cloud is empty");
  }
}

}  // namespace
}  // namespace scallop

// ---- the node ----
namespace scallop {
namespace cloud_nodes {
NodeDecl make_knn_node();
}  // namespace cloud_nodes
using cloud_nodes::make_knn_node;
namespace {

using test::run_node;

TEST(KnnNode, ComputesNeighbours) {
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = random_cloud(200, 4);
  const NodeDecl d = make_knn_node();
  EXPECT_EQ(d.type, "cloud.knn");
  auto out = run_node(d, {{"k", 6}}, {{"cloud", cloud}});
  auto nb = std::dynamic_pointer_cast<const Neighborhoods>(out.at("neighbors"));
  ASSERT_TRUE(nb);
  expect_same(*nb, brute_force(cloud->points, 6));
}

TEST(KnnNode, ErrorTexts) {
  const NodeDecl d = make_knn_node();
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = random_cloud(5, 4);
  try {
    run_node(d, {}, {{"cloud", cloud}});
    FAIL() << "no exception";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "k = 12 needs at least 13 points; the cloud has 5");
  }
  try {
    run_node(d, {}, {{"cloud", std::make_shared<PointCloud>()}});
    FAIL() << "no exception";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "the cloud is empty");
  }
}

}  // namespace
}  // namespace scallop
