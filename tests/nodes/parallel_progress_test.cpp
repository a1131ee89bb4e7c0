#include "engine/parallel_progress.h"

#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/knn.h"
#include "nodes/param/laplacian.h"

namespace scallop {
namespace {

// Reports from a parallel loop: non-decreasing, within [from, to], the last one exactly `to`.
void expect_well_formed(const std::vector<double>& seen, double from, double to) {
  ASSERT_FALSE(seen.empty());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_GE(seen[i], from);
    EXPECT_LE(seen[i], to);
    if (i) EXPECT_GE(seen[i], seen[i - 1]);
  }
  EXPECT_DOUBLE_EQ(seen.back(), to);
}

TEST(ParallelProgress, ReportsAreOrderedAndEndAtTheTop) {
  std::vector<double> seen;  // not thread-safe on purpose: one report at a time
  const std::function<void(double)> report = [&](double f) { seen.push_back(f); };
  ParallelProgress done(report, 100000, 0.25, 0.75);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, 100000, 64), [&](const auto& r) {
    done.done(r.size());
  });
  expect_well_formed(seen, 0.25, 0.75);
}

TEST(ParallelProgress, NoCallbackIsFine) {
  const std::function<void(double)> none;
  ParallelProgress done(none, 10);
  done.done(10);
}

// The long cloud steps report through it: k nearest neighbours, boundary, Laplacian.
TEST(ParallelProgress, KnnBoundaryAndLaplacianReportTheirProgress) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 30);
  std::vector<Eigen::Vector3d> P, N;
  for (int i = 0; i < 20000; ++i) {
    P.emplace_back(u(rng), u(rng), 0);
    N.emplace_back(0, 0, 1);
  }
  std::vector<double> seen;
  const std::function<void(double)> report = [&](double f) { seen.push_back(f); };
  const Neighborhoods nb = compute_knn(P, 12, report);
  expect_well_formed(seen, 0, 1);
  seen.clear();
  detect_boundary(P, N, nb, 1.5, true, report);
  expect_well_formed(seen, 0, 1);
  seen.clear();
  build_laplacian(P, N, nb, LaplacianScheme::Optimal, 0, 1e-3, report);
  expect_well_formed(seen, 0, 1);
}

}  // namespace
}  // namespace scallop
