#include "nodes/mesh/reconstruct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <thread>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// n points spread evenly over a sphere (Fibonacci lattice), outward normals, radial noise sigma.
void sphere_cloud(int n, double R, const Eigen::Vector3d& centre, double sigma, std::vector<Eigen::Vector3d>& P,
                  std::vector<Eigen::Vector3d>& N, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
    const Eigen::Vector3d u(r * std::cos(golden * i), r * std::sin(golden * i), z);
    P.push_back(centre + (R + (sigma > 0 ? noise(rng) : 0.0)) * u);
    N.push_back(u);
  }
}

double signed_volume(const Mesh& m) {
  double v = 0;
  for (std::size_t f = 0; f < m.num_faces(); ++f) v += m.vertices[m.face(f)[0]].dot(face_area_vector(m, f)) / 6.0;
  return v;
}

TEST(Reconstruct, AdvancingFrontInterpolatesASphereIntoOneClosedOutwardSurface) {
  std::vector<Eigen::Vector3d> P, N;
  sphere_cloud(3000, 10.0, Eigen::Vector3d::Zero(), 0.0, P, N);
  ReconstructResult r = reconstruct_surface(P, N, {});
  const MeshTopology t = mesh_topology(r.mesh, mesh_edges(r.mesh));
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(r.unused_points, 0u);
  // Every vertex is a cloud point: on the sphere.
  for (const auto& v : r.mesh.vertices) EXPECT_NEAR(v.norm(), 10.0, 1e-12);
  // Outward, and the volume of the inscribed polyhedron is just under the ball's.
  const double ball = 4.0 / 3.0 * M_PI * 1000.0;
  EXPECT_GT(signed_volume(r.mesh), 0.99 * ball);
  EXPECT_LT(signed_volume(r.mesh), ball);
  EXPECT_EQ(r.distance_max, 0.0);
}

// The front breaks ties between equal candidates by where the triangulation's cells lie in memory,
// which differs between threads (each has its own heap state): a grid on a box's faces is full of
// such ties. Whatever thread runs it, the same cloud must give the same faces in the same order.
TEST(Reconstruct, AdvancingFrontGivesTheSameFacesOnEveryThread) {
  std::vector<Eigen::Vector3d> P, N;
  for (int a = 0; a <= 20; ++a)
    for (int b = 0; b <= 20; ++b)
      for (int axis = 0; axis < 3; ++axis)
        for (double side : {0.0, 10.0}) {
          Eigen::Vector3d p, n = Eigen::Vector3d::Zero();
          p[axis] = side;
          p[(axis + 1) % 3] = 0.5 * a;
          p[(axis + 2) % 3] = 0.5 * b;
          n[axis] = side > 0 ? 1 : -1;
          if (a == 0 || a == 20 || b == 0 || b == 20) continue;  // the edges and corners are on two faces
          P.push_back(p);
          N.push_back(n);
        }
  const Mesh first = reconstruct_surface(P, N, {}).mesh;
  ASSERT_GT(first.num_faces(), 1000u);
  std::vector<Mesh> on_threads(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      // A heap in another state than the main thread's: blocks of many sizes, among them the
      // front's own records' (about 100 bytes), every other one freed and the rest kept.
      std::vector<std::vector<char>> churn;
      for (int i = 0; i < 2000 * (t + 1); ++i) churn.emplace_back(std::size_t(i % 3 ? 100 : 64 + 97 * i % 4000));
      for (std::size_t i = t % 2; i < churn.size(); i += 2) churn[i].clear(), churn[i].shrink_to_fit();
      on_threads[t] = reconstruct_surface(P, N, {}).mesh;
    });
  for (auto& t : threads) t.join();
  for (const Mesh& m : on_threads) {
    EXPECT_EQ(m.vertices, first.vertices);
    EXPECT_EQ(m.face_start, first.face_start);
    EXPECT_EQ(m.face_vertices, first.face_vertices);
  }
}

TEST(Reconstruct, AdvancingFrontGivesTheSameFacesWhateverRanBefore) {
  // 30 000 random points on a 60 x 40 x 15 block's faces. The front breaks ties by where its
  // records lie in memory, which depends on what the process did before: run inside this one,
  // a second reconstruction after the heap was churned gave other faces (the test failed); in a
  // process of its own (scallop-advancing-front) it gives the same.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> P, N;
  const Eigen::Vector3d size(60, 40, 15);
  const double area[3] = {size.y() * size.z(), size.x() * size.z(), size.x() * size.y()};
  while (P.size() < 30000) {
    const int axis = u(rng) * (area[0] + area[1] + area[2]) < area[0] ? 0 : (u(rng) < area[1] / (area[1] + area[2]) ? 1 : 2);
    Eigen::Vector3d p(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z()), n = Eigen::Vector3d::Zero();
    const bool high = u(rng) < 0.5;
    p[axis] = high ? size[axis] : 0;
    n[axis] = high ? 1 : -1;
    P.push_back(p), N.push_back(n);
  }
  const Mesh first = reconstruct_surface(P, N, {}).mesh;
  std::vector<std::vector<char>> churn;
  for (int i = 0; i < 200000; ++i) churn.emplace_back(std::size_t(i % 3 ? 100 : 64 + 97 * i % 4000));
  for (std::size_t i = 0; i < churn.size(); i += 2) churn[i].clear(), churn[i].shrink_to_fit();
  const Mesh second = reconstruct_surface(P, N, {}).mesh;
  EXPECT_EQ(second.face_vertices, first.face_vertices);
}

TEST(Reconstruct, PoissonOfANoisySphereIsWithinSigmaAndOnePercentOfTheRadius) {
  std::vector<Eigen::Vector3d> P, N;
  const double R = 10.0, sigma = 0.02;
  sphere_cloud(6000, R, Eigen::Vector3d(5, -3, 2), sigma, P, N);
  ReconstructOptions o;
  o.method = ReconstructMethod::poisson;
  ReconstructResult r = reconstruct_surface(P, N, o);
  // The mesh's radius is within sigma + 1% of R; each vertex within 4 sigma + 1% (the implicit
  // surface follows the noise a little: measured mean |r - R| 0.026, p99 0.096, max 0.131).
  const Eigen::Vector3d centre(5, -3, 2);
  double sum = 0, worst = 0;
  for (const auto& v : r.mesh.vertices) {
    sum += (v - centre).norm();
    worst = std::max(worst, std::abs((v - centre).norm() - R));
  }
  EXPECT_LE(std::abs(sum / static_cast<double>(r.mesh.num_vertices()) - R), sigma + 0.01 * R);
  EXPECT_LE(worst, 4 * sigma + 0.01 * R);
  const MeshTopology t = mesh_topology(r.mesh, mesh_edges(r.mesh));
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(r.trimmed_faces, 0u);
  EXPECT_GT(signed_volume(r.mesh), 0.0);
  // The surface mesher's chords stay within poisson_approximation spacings of the implicit surface.
  EXPECT_LE(r.distance_p99, 3 * sigma + o.poisson_approximation * r.spacing);
}

TEST(Reconstruct, TwoSeparateSpheresGiveTwoComponents) {
  std::vector<Eigen::Vector3d> P, N;
  sphere_cloud(1500, 5.0, Eigen::Vector3d::Zero(), 0.0, P, N);
  sphere_cloud(1500, 5.0, Eigen::Vector3d(20, 0, 0), 0.0, P, N);
  ReconstructResult r = reconstruct_surface(P, N, {});
  EXPECT_EQ(mesh_topology(r.mesh, mesh_edges(r.mesh)).components, 2);
}

TEST(Reconstruct, NormalsThatFlipBetweenNeighboursAreMeasured) {
  std::vector<Eigen::Vector3d> P, N;
  sphere_cloud(2000, 10.0, Eigen::Vector3d::Zero(), 0.0, P, N);
  EXPECT_EQ(normal_disagreement(P, N), 0.0);
  std::mt19937 rng(3);
  for (auto& n : N)
    if (rng() % 2) n = -n;  // each normal flipped with probability 1/2: half the pairs disagree
  EXPECT_NEAR(normal_disagreement(P, N), 0.5, 0.05);
}

std::string error_of(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                     ReconstructMethod method) {
  ReconstructOptions o;
  o.method = method;
  try {
    reconstruct_surface(P, N, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Reconstruct, BadInputIsRefusedWithWhatToDo) {
  std::vector<Eigen::Vector3d> P, N;
  sphere_cloud(2000, 10.0, Eigen::Vector3d::Zero(), 0.0, P, N);
  EXPECT_EQ(error_of({P.begin(), P.begin() + 3}, {}, ReconstructMethod::advancing_front),
            "the cloud has 3 points; reconstruction needs at least 10");
  EXPECT_EQ(error_of(P, {}, ReconstructMethod::poisson),
            "method poisson needs normals oriented consistently over the whole cloud, and the cloud has none: "
            "add cloud.normals (orientation mst) before mesh.reconstruct, or use method advancing_front");
  std::vector<Eigen::Vector3d> flipped = N;
  for (std::size_t i = 0; i < flipped.size(); i += 37) flipped[i] = -flipped[i];  // 1 in 37: ~5% of pairs
  const std::string flips = error_of(P, flipped, ReconstructMethod::poisson);
  EXPECT_EQ(flips.substr(0, 43), "the normals are not oriented consistently: ");
  EXPECT_NE(flips.find("% of neighbouring normals point against each other (at most 2% expected); Poisson needs "
                       "them all outward: compute them with cloud.normals orientation mst"),
            std::string::npos)
      << flips;
  std::vector<Eigen::Vector3d> nan = P;
  nan[7].x() = std::nan("");
  EXPECT_EQ(error_of(nan, {}, ReconstructMethod::advancing_front),
            "point 7 has a NaN or infinite coordinate: run cloud.clean first");
  std::vector<Eigen::Vector3d> line, plane;
  for (int i = 0; i < 100; ++i) line.push_back({0.1 * i, 0, 0});
  EXPECT_EQ(error_of(line, {}, ReconstructMethod::advancing_front).substr(0, 32), "the cloud is one-dimensional: it");
  for (int i = 0; i < 400; ++i) plane.push_back({0.1 * (i % 20), 0.1 * (i / 20), 0});
  EXPECT_EQ(error_of(plane, {}, ReconstructMethod::advancing_front).substr(0, 36),
            "the points lie exactly in one plane;");
}

// Distance from p to the surface of the cube [-h, h]^3.
double cube_distance(const Eigen::Vector3d& p, double h) {
  const Eigen::Vector3d q = p.cwiseAbs() - Eigen::Vector3d::Constant(h);
  const double outside = q.cwiseMax(0.0).norm();
  return outside > 0 ? outside : -q.maxCoeff();
}

TEST(Reconstruct, BilateralSmoothingFlattensANoisyCubesFaces) {
  // 12 000 points on a cube of edge 10, noise sigma 0.05 along the face normals.
  std::vector<Eigen::Vector3d> P, N;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::uniform_real_distribution<double> along(-5, 5);
  for (int i = 0; i < 12000; ++i) {
    const int axis = (i % 6) / 2;
    const double side = i % 2 ? 1.0 : -1.0;
    Eigen::Vector3d p(along(rng), along(rng), along(rng)), n = Eigen::Vector3d::Zero();
    p[axis] = side * (5 + noise(rng));
    n[axis] = side;
    P.push_back(p);
    N.push_back(n);
  }
  auto mean_error = [](const Mesh& m) {
    double s = 0;
    for (const auto& v : m.vertices) s += cube_distance(v, 5.0);
    return s / static_cast<double>(m.num_vertices());
  };
  const double raw = mean_error(reconstruct_surface(P, N, {}).mesh);
  EXPECT_NEAR(raw, 0.05 * std::sqrt(2.0 / M_PI), 0.003);  // E|noise| of a Gaussian
  ReconstructOptions o;
  o.smooth_iterations = 2;
  // Measured 0.0081 (k = 24): the noise falls about 5x, the edges stay (cube_distance counts them).
  EXPECT_LT(mean_error(reconstruct_surface(P, N, o).mesh), 0.25 * raw);
}

}  // namespace

// ---- the node ----
namespace mesh_nodes {
NodeDecl make_reconstruct_node();
}  // namespace mesh_nodes
namespace {

TEST(ReconstructNode, MeshesACloudAndReportsItsTopologyAndDistances) {
  const NodeDecl d = mesh_nodes::make_reconstruct_node();
  EXPECT_EQ(d.type, "mesh.reconstruct");
  auto cloud = std::make_shared<PointCloud>();
  sphere_cloud(2000, 10.0, Eigen::Vector3d::Zero(), 0.0, cloud->points, cloud->normals);
  auto out = test::run_node(d, {}, {{"cloud", cloud}});
  auto mesh = std::dynamic_pointer_cast<const Mesh>(out.at("mesh"));
  ASSERT_TRUE(mesh);
  EXPECT_EQ(mesh->num_vertices(), 2000u);
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_EQ(r["method"], "advancing_front");
  EXPECT_EQ(r["faces"], mesh->num_faces());
  EXPECT_EQ(r["components"], 1);
  EXPECT_EQ(r["boundary_loops"], 0);
  EXPECT_EQ(r["genus"], 0);
  EXPECT_EQ(r["distance"]["max"], 0.0);
}

TEST(ReconstructNode, ErrorsAreNodeErrors) {
  auto cloud = std::make_shared<PointCloud>();
  sphere_cloud(200, 10.0, Eigen::Vector3d::Zero(), 0.0, cloud->points, cloud->normals);
  cloud->normals.clear();
  try {
    test::run_node(mesh_nodes::make_reconstruct_node(), {{"smooth_iterations", 2}}, {{"cloud", cloud}});
    FAIL() << "no exception";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()),
              "smoothing (smooth_iterations > 0) needs normals, and the cloud has none: add cloud.normals "
              "before mesh.reconstruct, or set smooth_iterations 0");
  }
}

}  // namespace
}  // namespace scallop
