#include "nodes/cloud/boundary.h"

#include <gtest/gtest.h>

#include <numbers>

#include "nodes/cloud/knn.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

TEST(Boundary, DiskRimIsFoundAndTheInsideIsNot) {
  PointCloud c = test::random_disk(3000, 10, 41);
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  ASSERT_EQ(b.size(), c.size());
  // Spacing ~0.32 mm. A Poisson-like sampling has voids, and points around a void see a real
  // gap: a few inside points are flagged (order_boundary_loops drops such void "holes"). The rim
  // is covered: every 10 degrees of rim has boundary points.
  std::vector<int> sector(36, 0);
  int count = 0, inside = 0, inside_flagged = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    double r = c.points[i].head<2>().norm();
    if (r < 8) ++inside, inside_flagged += b[i];
    if (!b[i] || r < 9) continue;
    ++count;
    double a = std::atan2(c.points[i].y(), c.points[i].x()) + std::numbers::pi;
    sector[std::min(35, static_cast<int>(a / (2 * std::numbers::pi) * 36))]++;
  }
  std::printf("[ boundary ] %d rim points, %d of %d inside points flagged\n", count, inside_flagged, inside);
  EXPECT_LT(inside_flagged, 0.03 * inside);
  EXPECT_GT(count, 200);
  for (int s = 0; s < 36; ++s) EXPECT_GT(sector[s], 0) << "sector " << s;
}

TEST(Boundary, GridEdgesExactly) {
  PointCloud c = test::jittered_grid(10, 10, 0.5, 0.5, 0.0, 42);
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const auto& p = c.points[i];
    bool edge = p.x() < 1e-9 || p.y() < 1e-9 || p.x() > 10 - 1e-9 || p.y() > 10 - 1e-9;
    EXPECT_EQ(b[i] != 0, edge) << p.transpose();
  }
}

TEST(Boundary, ClosedSphereHasNone) {
  PointCloud c;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {  // Fibonacci sphere
    double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z), a = i * std::numbers::pi * (3 - std::sqrt(5.0));
    c.points.emplace_back(10 * r * std::cos(a), 10 * r * std::sin(a), 10 * z);
    c.normals.push_back(c.points.back().normalized());
  }
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  for (auto f : b) EXPECT_EQ(f, 0);
}

TEST(Boundary, Errors) {
  PointCloud c = test::random_disk(100, 10, 43);
  auto nb = compute_knn(c.points, 8);
  try {
    detect_boundary(c.points, {}, nb, std::numbers::pi / 2);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "boundary detection needs normals (the cloud has 0 normals for 100 points); run cloud.normals first");
  }
  auto nb2 = compute_knn(c.points, 2);
  EXPECT_THROW(detect_boundary(c.points, c.normals, nb2, 1.5), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
