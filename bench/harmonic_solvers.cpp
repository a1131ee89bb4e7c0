// The harmonic map of a cloud by each solver, side by side: time, relative residual, and the
// largest change of (u,v) against UMFPACK's direct LU (issue 15: "at the same map accuracy").
//
//   harmonic_solvers CLOUD.ply [K] [SOLVERS]    K default 16; SOLVERS default two_level,direct
//
// The cloud goes through the zig-zag graph's own steps, as plain functions: cloud.clean (spatial
// order), k nearest neighbours, PCA normals oriented up, boundary, loops, the rectangle's boundary
// map, the optimal-weights Laplacian; then param.harmonic's band solve with each solver.
#include <chrono>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/boundary_order.h"
#include "nodes/cloud/clean.h"
#include "nodes/cloud/knn.h"
#include "nodes/cloud/normals.h"
#include "nodes/io/read_cloud.h"
#include "nodes/param/boundary_map.h"
#include "nodes/param/harmonic.h"
#include "nodes/param/laplacian.h"

int main(int argc, char** argv) {
  using namespace scallop;
  if (argc < 2) {
    std::fprintf(stderr, "usage: harmonic_solvers CLOUD.ply [K] [two_level,direct,...]\n");
    return 2;
  }
  const int k = argc > 2 ? std::stoi(argv[2]) : 16;
  std::vector<std::string> solvers{"two_level", "direct"};
  if (argc > 3) {
    solvers.clear();
    std::stringstream list(argv[3]);
    for (std::string s; std::getline(list, s, ',');) solvers.push_back(s);
  }
  const PointCloud cloud = clean_cloud(read_cloud(argv[1]), CleanOptions{});
  const auto& P = cloud.points;
  const Neighborhoods nbrs = compute_knn(P, k);
  std::vector<Eigen::Vector3d> N = pca_normals(P, nbrs);
  orient_normals_up(N);
  const auto is_b = detect_boundary(P, N, nbrs, std::numbers::pi / 2);
  const auto loops = order_boundary_loops(P, N, nbrs, is_b);
  const UVMap b = map_boundary(P, loops[0], BoundaryDomain::Rectangle);
  const auto L = build_laplacian(P, N, nbrs, LaplacianScheme::Optimal);
  std::printf("%zu points, k = %d, domain %.3f x %.3f\n", P.size(), k, b.width, b.height);
  std::vector<UVMap> maps;
  for (const std::string& name : solvers) {
    const auto t0 = std::chrono::steady_clock::now();
    maps.push_back(solve_harmonic_band(L, P, N, is_b, loops, b, parse_harmonic_solver(name)));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double change = 0;
    for (std::size_t i = 0; i < P.size(); ++i) change = std::max(change, (maps.back().uv[i] - maps[0].uv[i]).norm());
    std::printf("%-10s %8.3f s   relative residual %.2e   largest |uv - uv(%s)| %.2e\n", name.c_str(), s,
                maps.back().residual, solvers[0].c_str(), change);
  }
  return 0;
}
