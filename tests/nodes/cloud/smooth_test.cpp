#include "nodes/cloud/smooth.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/knn.h"
#include "nodes/param/laplacian.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

TEST(Smooth, NoisyPlaneGetsFlatterAlongNormalsOnly) {
  PointCloud c = test::random_disk(2000, 10, 61);
  std::mt19937 rng(62);
  std::normal_distribution<double> noise(0, 0.05);
  for (auto& p : c.points) p.z() = noise(rng);
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  auto rms = [](const std::vector<Eigen::Vector3d>& P) {
    double s = 0;
    for (const auto& p : P) s += p.z() * p.z();
    return std::sqrt(s / P.size());
  };
  auto out = smooth_cloud(c.points, c.normals, L, b, 2, 0.5);
  ASSERT_EQ(out.size(), c.size());
  std::printf("[ smooth ] rms z %.4f -> %.4f\n", rms(c.points), rms(out));
  EXPECT_LT(rms(out), 0.6 * rms(c.points));
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_EQ(out[i].x(), c.points[i].x());  // normals are +Z: x, y never move
    EXPECT_EQ(out[i].y(), c.points[i].y());
    if (b[i]) {
      EXPECT_EQ(out[i].z(), c.points[i].z());
    }
  }
}

TEST(Smooth, PlaneStaysPut) {
  PointCloud c = test::random_disk(500, 10, 63);
  for (auto& p : c.points) p.z() = 0.3 * p.x() - 0.2 * p.y() + 1;
  Eigen::Vector3d n = Eigen::Vector3d(-0.3, 0.2, 1).normalized();
  c.normals.assign(c.size(), n);
  auto nb = compute_knn(c.points, 12);
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  auto out = smooth_cloud(c.points, c.normals, L, {}, 3, 1.0);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT((out[i] - c.points[i]).norm(), 1e-9);
}

TEST(Smooth, Errors) {
  PointCloud c = test::random_disk(50, 10, 64);
  auto nb = compute_knn(c.points, 6);
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Uniform);
  EXPECT_THROW(smooth_cloud(c.points, c.normals, L, {}, 1, 1.5), std::invalid_argument);
  EXPECT_THROW(smooth_cloud(c.points, c.normals, L, {}, -1, 0.5), std::invalid_argument);
  EXPECT_THROW(smooth_cloud(c.points, {}, L, {}, 1, 0.5), std::invalid_argument);
  EXPECT_THROW(smooth_cloud(c.points, c.normals, L, std::vector<std::uint8_t>(3), 1, 0.5), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
