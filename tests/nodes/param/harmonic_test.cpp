#include "nodes/param/harmonic.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <complex>
#include <tbb/parallel_for.h>
#include <vector>

#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "nodes/cloud/trim_steep.h"
#include "nodes/param/laplacian.h"
#include "nodes/types/param.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

using cd = std::complex<double>;

// Least-squares similarity uv = a z + b (complex a: rotation and scale) fitted to the points with
// |p| < r_fit; returns the scale |a| and the largest |uv - (a z + b)| / |a| (mm) over the points
// with |p| < r_eval.
double similarity_error(const PointCloud& c, const std::vector<Eigen::Vector2d>& uv, double r_fit, double r_eval,
                        double* scale) {
  std::vector<std::size_t> fit;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (c.points[i].head<2>().norm() < r_fit) fit.push_back(i);
  Eigen::MatrixXcd A(fit.size(), 2);
  Eigen::VectorXcd y(fit.size());
  for (std::size_t r = 0; r < fit.size(); ++r) {
    A(r, 0) = cd(c.points[fit[r]].x(), c.points[fit[r]].y());
    A(r, 1) = 1.0;
    y(r) = cd(uv[fit[r]].x(), uv[fit[r]].y());
  }
  Eigen::VectorXcd ab = A.colPivHouseholderQr().solve(y);
  *scale = std::abs(ab(0));
  double err = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (c.points[i].head<2>().norm() < r_eval)
      err = std::max(err, std::abs(ab(0) * cd(c.points[i].x(), c.points[i].y()) + ab(1) - cd(uv[i].x(), uv[i].y())));
  return err / *scale;
}

TEST(Harmonic, FlatDiskMapsToASimilarDisk) {
  // Points uniform in a disk of radius 10, the ordered rim mapped to a circle by chord length:
  // the harmonic map is a similarity uv = s R p + t (closed form), with s = L / (2 pi 10), L the
  // length of the (jagged) rim polygon. Only the optimal weights have linear precision; the graph
  // and heat Laplacians are biased by the random sampling, so they get a looser bound.
  PointCloud c = test::random_disk(3000, 10, 11);
  for (auto scheme : {LaplacianScheme::Optimal, LaplacianScheme::Heat, LaplacianScheme::Uniform}) {
    auto p = test::parameterize(c, 12, BoundaryDomain::Disk, scheme);
    ASSERT_EQ(p.map.uv.size(), c.size());
    EXPECT_LT(p.map.residual, 1e-10);
    double s = 0;
    double all = similarity_error(c, p.map.uv, 10, 11, &s);
    double inner = similarity_error(c, p.map.uv, 10, 8, &s);
    EXPECT_NEAR(s, p.map.radius / 10, 0.03 * s) << to_string(scheme);
    std::printf("[ disk ] %-8s scale %.4f (L/2piR %.4f), max deviation from the similarity: %.3f mm, "
                "%.3f mm within r < 8\n", to_string(scheme).c_str(), s, p.map.radius / 10, all, inner);
    const bool optimal = scheme == LaplacianScheme::Optimal;
    EXPECT_LT(all, optimal ? 0.8 : 2.5) << to_string(scheme);
    EXPECT_LT(inner, optimal ? 0.4 : 2.0) << to_string(scheme);
    // Outer loop points sit on the circle or, where the loop zig-zags inwards, just inside it
    // (the band keeps its depth; the spacing is ~0.3 mm).
    for (std::size_t j = 0; j < p.map.outer_loop.size(); ++j) {
      EXPECT_LE(p.map.uv[p.map.outer_loop[j]].norm(), p.map.radius + 1e-9);
      EXPECT_GE(p.map.uv[p.map.outer_loop[j]].norm(), p.map.radius - 1.0);
      EXPECT_EQ(p.map.uv[p.map.outer_loop[j]], p.map.boundary_uv[j]);
    }
  }
}

TEST(Harmonic, IterativeSolversAgreeWithDirect) {
  PointCloud c = test::random_disk(1500, 10, 12);
  auto d = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal, HarmonicSolver::Direct);
  for (auto s : {HarmonicSolver::BiCGSTAB, HarmonicSolver::GMRES}) {
    auto it = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal, s);
    EXPECT_LT(it.map.residual, 1e-6);
    double diff = 0;
    for (std::size_t i = 0; i < c.size(); ++i) diff = std::max(diff, (it.map.uv[i] - d.map.uv[i]).norm());
    EXPECT_LT(diff, 1e-5);
  }
}

TEST(Harmonic, TheTwoLevelSolveIsAsExactAsTheDirectOne) {
  // From 50 000 unknowns the default solver is the two-level GMRES (below, the direct LU).
  PointCloud c = test::random_disk(60000, 40, 16);
  auto d = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal, HarmonicSolver::Direct);
  auto t = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal, HarmonicSolver::TwoLevel);
  EXPECT_LT(t.map.residual, 1e-10);
  double diff = 0;
  for (std::size_t i = 0; i < c.size(); ++i) diff = std::max(diff, (t.map.uv[i] - d.map.uv[i]).norm());
  EXPECT_GT(diff, 0);  // it did not take the direct path
  EXPECT_LT(diff, 1e-8 * std::max(d.map.width, d.map.height));
}

TEST(Harmonic, SolvesAtOnceInSeveralThreadsGiveTheSameMap) {
  // A batch solves many parts' maps at once. UMFPACK works through the BLAS, and Debian's serial
  // OpenBLAS has no locks: unguarded, two factorisations at once could share its buffers (a
  // batch's harmonic node failed with a relative residual of 3e-5). Every map must be the one a
  // solve alone gives, bit for bit.
  PointCloud c = test::random_disk(6000, 20, 17);
  const auto alone = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal,
                                        HarmonicSolver::Direct);
  std::vector<test::Pipeline> together(8);
  tbb::parallel_for(std::size_t(0), together.size(), [&](std::size_t k) {
    together[k] = test::parameterize(c, 12, BoundaryDomain::Rectangle, LaplacianScheme::Optimal,
                                     HarmonicSolver::Direct);
  });
  for (const auto& t : together) {
    EXPECT_LT(t.map.residual, 1e-10);
    ASSERT_EQ(t.map.uv.size(), alone.map.uv.size());
    for (std::size_t i = 0; i < c.size(); ++i) ASSERT_EQ(t.map.uv[i], alone.map.uv[i]) << i;
  }
}

TEST(Harmonic, AffineBoundaryGivesAffineMapWithOptimalWeights) {
  // Linear precision: when the boundary values are an affine function of the positions, the
  // optimal-weights harmonic map is that affine function everywhere.
  PointCloud c = test::random_disk(1500, 10, 13);
  auto nb = compute_knn(c.points, 12);
  auto is_b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, is_b);
  UVMap b;
  b.domain = "disk";
  b.outer_loop = loops[0];
  auto f = [](const Eigen::Vector3d& p) { return Eigen::Vector2d(0.5 * p.x() - 0.2 * p.y() + 1, 0.3 * p.x() + 2 * p.y()); };
  for (int i : b.outer_loop) b.boundary_uv.push_back(f(c.points[i]));
  auto m = solve_harmonic(build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal), b);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT((m.uv[i] - f(c.points[i])).norm(), 1e-8);
}

TEST(Harmonic, DisconnectedClusterIsAClearError) {
  PointCloud c = test::random_disk(800, 10, 14);
  // A far-away cluster of 20 points whose 12 neighbours are all inside the cluster.
  for (int i = 0; i < 20; ++i) c.points.emplace_back(100 + 0.1 * (i % 5), 0.1 * (i / 5), 0), c.normals.push_back(Eigen::Vector3d::UnitZ());
  auto nb = compute_knn(c.points, 12);
  UVMap b;
  std::vector<int> outer;
  for (int i = 0; i < 800; ++i)
    if (c.points[i].head<2>().norm() > 9.5) outer.push_back(i);
  b.outer_loop = outer;
  for (int i : outer) b.boundary_uv.push_back(c.points[i].head<2>());
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Uniform);
  try {
    solve_harmonic(L, b);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not connected to the outer boundary"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(a piece of the cloud apart from the patch? cloud.trim_steep keeps the "
                                         "largest connected piece and reports the rest)"),
              std::string::npos)
        << e.what();
  }
  // The advice works: the trim keeps the disk and leaves the cluster out.
  const TrimSteepResult trimmed = trim_steep(c.points, TrimSteepOptions{});
  EXPECT_EQ(trimmed.kept.size(), 800u);
  EXPECT_EQ(trimmed.cut_off, 20u);
  EXPECT_EQ(trimmed.kept.back(), 799u);
}

TEST(Harmonic, ADenseClusterWhoseNeighboursAreAllInsideItIsJoinedToThePointsAroundIt) {
  // 20 points 0.05 apart inside the disk (spacing about 0.6): their 12 nearest neighbours are all
  // among themselves, so their rows lead nowhere (as at a scan's overlap), while the points around
  // them name them. Without `join` that is the error; with it the join is asked for exactly those
  // points and, the rows rebuilt with the optimal scheme, an affine boundary still gives the
  // affine map everywhere.
  PointCloud c = test::random_disk(800, 10, 14);
  for (int i = 0; i < 20; ++i)
    c.points.emplace_back(3 + 0.05 * (i % 5), 2 + 0.05 * (i / 5), 0), c.normals.push_back(Eigen::Vector3d::UnitZ());
  auto nb = compute_knn(c.points, 12);
  UVMap b;
  b.domain = "disk";
  for (int i = 0; i < 800; ++i)
    if (c.points[i].head<2>().norm() > 9.5) b.outer_loop.push_back(i);
  auto f = [](const Eigen::Vector3d& p) { return Eigen::Vector2d(0.5 * p.x() - 0.2 * p.y() + 1, 0.3 * p.x() + 2 * p.y()); };
  for (int i : b.outer_loop) b.boundary_uv.push_back(f(c.points[i]));
  const auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  EXPECT_THROW(solve_harmonic(L, b, HarmonicSolver::Direct), std::runtime_error);
  std::vector<int> asked;
  const UVMap m = solve_harmonic(L, b, HarmonicSolver::Direct, {}, [&](const std::vector<int>& points) {
    asked = points;
    return join_rows_both_ways(L, c.points, c.normals, LaplacianScheme::Optimal, 0, 1e-3, points);
  });
  std::vector<int> cluster;
  for (int i = 800; i < 820; ++i) cluster.push_back(i);
  EXPECT_EQ(asked, cluster);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT((m.uv[i] - f(c.points[i])).norm(), 1e-8) << "point " << i;
}

TEST(Harmonic, NodeJoinsRowsThatLeadNowhereAndSaysHowMany) {
  // The node, as the shipped graphs run it (the band fixed): the same dense cluster is joined with
  // the Laplacian's own scheme, and the count reaches the terminal; the map is finite everywhere.
  PointCloud c = test::random_disk(800, 10, 14);
  for (int i = 0; i < 20; ++i)
    c.points.emplace_back(3 + 0.05 * (i % 5), 2 + 0.05 * (i / 5), 0), c.normals.push_back(Eigen::Vector3d::UnitZ());
  const auto nb = compute_knn(c.points, 12);
  BoundaryLoops loops;
  loops.is_boundary = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  loops.loops = order_boundary_loops(c.points, c.normals, nb, loops.is_boundary);
  Laplacian lap;
  lap.scheme = "optimal";
  lap.regularization = 1e-3;
  lap.L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  const NodeDecl& d = *builtin_registry().find("param.harmonic");
  nlohmann::json params;
  for (const auto& p : d.params) params[p.name] = p.default_value;
  std::vector<std::string> said;
  NodeContext ctx(d, "harmonic", "part", params,
                  {{"laplacian", std::make_shared<const Laplacian>(lap)},
                   {"map", std::make_shared<const UVMap>(map_boundary(c.points, loops.loops[0], BoundaryDomain::Disk))},
                   {"loops", std::make_shared<const BoundaryLoops>(loops)},
                   {"cloud", std::make_shared<const PointCloud>(c)}},
                  nullptr, [&](const std::string& m) { said.push_back(m); });
  d.run(ctx);
  const auto map = std::dynamic_pointer_cast<const UVMap>(ctx.take_outputs().at("map"));
  ASSERT_TRUE(map);
  for (const auto& q : map->uv) ASSERT_TRUE(q.allFinite());
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0],
            "20 points had their nearest neighbours all among themselves (a denser region beside a sparser one), so "
            "no row led from them to the boundary: their rows were rebuilt over their neighbours both ways, the "
            "points they name and those naming them");
}

TEST(Harmonic, FixedPointsKeepTheirValues) {
  // Extra Dirichlet points, and one replacing an outer-loop value: all kept exactly, and the
  // returned boundary_uv holds the values used.
  PointCloud c = test::random_disk(800, 10, 15);
  auto nb = compute_knn(c.points, 12);
  auto is_b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, is_b);
  UVMap b = map_boundary(c.points, loops[0], BoundaryDomain::Disk);
  int interior = -1;
  for (std::size_t i = 0; i < c.size() && interior < 0; ++i)
    if (c.points[i].head<2>().norm() < 2) interior = static_cast<int>(i);
  ASSERT_GE(interior, 0);
  std::vector<std::pair<int, Eigen::Vector2d>> fixed = {{interior, {0.5, -0.25}}, {loops[0][3], {1, 2}}};
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  auto m = solve_harmonic(L, b, HarmonicSolver::Direct, fixed);
  EXPECT_EQ(m.uv[interior], Eigen::Vector2d(0.5, -0.25));
  EXPECT_EQ(m.uv[loops[0][3]], Eigen::Vector2d(1, 2));
  EXPECT_EQ(m.boundary_uv[3], Eigen::Vector2d(1, 2));
  EXPECT_EQ(m.uv[loops[0][4]], b.boundary_uv[4]);
  EXPECT_THROW(solve_harmonic(L, b, HarmonicSolver::Direct, {{-1, {0, 0}}}), std::invalid_argument);
  EXPECT_THROW(solve_harmonic_band(L, std::vector<Eigen::Vector3d>(5), c.normals, is_b, loops, b), std::invalid_argument);
  // The band solve says what it is doing, in order, and ends at 1; with one factorisation for both
  // of its solves it gives the same map as without progress.
  std::vector<double> fractions;
  const UVMap with = solve_harmonic_band(L, c.points, c.normals, is_b, loops, b, HarmonicSolver::Direct,
                                         [&](double f, const std::string& msg) {
                                           EXPECT_FALSE(msg.empty());
                                           fractions.push_back(f);
                                         });
  EXPECT_EQ(fractions, (std::vector<double>{0.05, 0.6, 1.0}));
  EXPECT_EQ(with.uv, solve_harmonic_band(L, c.points, c.normals, is_b, loops, b, HarmonicSolver::Direct).uv);
}

TEST(Harmonic, BadInput) {
  Eigen::SparseMatrix<double, Eigen::RowMajor> L(5, 5);
  UVMap b;
  b.outer_loop = {0, 1};
  b.boundary_uv = {{0, 0}, {1, 0}};
  EXPECT_THROW(solve_harmonic(L, b), std::invalid_argument);
  b.outer_loop = {0, 1, 7};
  b.boundary_uv = {{0, 0}, {1, 0}, {0, 1}};
  EXPECT_THROW(solve_harmonic(L, b), std::invalid_argument);
  EXPECT_THROW(parse_harmonic_solver("cg"), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
