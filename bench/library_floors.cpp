// What the libraries alone take for the work the zig-zag graph's first nodes do on a cloud: the
// floor a node cannot go under, for bench/scale_bench.sh to print beside the graph's own times.
//
//   library_floors CLOUD.ply [K]     (K: neighbours, default 16 as the shipped graphs)
//
// Each step is the plain library call on the whole cloud, on all cores (oneTBB) where it is
// per point, nothing of the product's around it:
//   kd-tree build   nanoflann k-d tree over the points (single-threaded, as nanoflann builds)
//   knn queries     the K nearest neighbours of every point (nanoflann, oneTBB over points)
//   pca normals     3 x 3 covariance of each point's neighbours and its smallest eigenvector (Eigen)
//   optimal weights each point's K x K system (C + d tr C I) w = 1 (Eigen LDLT), the Laplacian's
//                   weights of Schmidt & Singh
//   sparse assembly an Eigen row-major sparse matrix of #P x (K + 1) entries from triplets
// Output: one line per step, "floor <name> <seconds>", and "floor sum <seconds>".
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <chrono>
#include <cstdio>
#include <nanoflann.hpp>
#include <string>
#include <vector>

#include "nodes/io/read_cloud.h"

namespace {

struct Cloud {
  const std::vector<Eigen::Vector3d>& p;
  std::size_t kdtree_get_point_count() const { return p.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return p[i][static_cast<int>(d)]; }
  template <class B> bool kdtree_get_bbox(B&) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, unsigned>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: library_floors CLOUD.ply [K]\n");
    return 2;
  }
  const int k = argc > 2 ? std::stoi(argv[2]) : 16;
  const std::vector<Eigen::Vector3d> P = scallop::read_cloud(argv[1]).points;
  const std::size_t n = P.size();
  double sum = 0;
  auto report = [&](const char* name, double s) {
    std::printf("floor %-16s %8.3f\n", name, s);
    sum += s;
  };

  auto t0 = std::chrono::steady_clock::now();
  Cloud cloud{P};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();
  report("kdtree_build", seconds_since(t0));

  std::vector<unsigned> idx(n * (k + 1));
  std::vector<double> d2(n * (k + 1));
  t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      tree.knnSearch(P[i].data(), k + 1, &idx[i * (k + 1)], &d2[i * (k + 1)]);
  });
  report("knn_queries", seconds_since(t0));
  // the point itself comes first; its neighbours are the k after it
  auto nb = [&](std::size_t i, int j) { return idx[i * (k + 1) + 1 + j]; };

  std::vector<Eigen::Vector3d> normal(n);
  t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      Eigen::Vector3d c = P[i];
      for (int j = 0; j < k; ++j) c += P[nb(i, j)];
      c /= k + 1;
      Eigen::Matrix3d C = (P[i] - c) * (P[i] - c).transpose();
      for (int j = 0; j < k; ++j) C += (P[nb(i, j)] - c) * (P[nb(i, j)] - c).transpose();
      normal[i] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvectors().col(0);
    }
  });
  report("pca_normals", seconds_since(t0));

  std::vector<double> W(n * k);
  t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    Eigen::MatrixXd D(3, k), C(k, k);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      for (int j = 0; j < k; ++j) D.col(j) = P[i] - P[nb(i, j)];
      C.noalias() = D.transpose() * D;
      C.diagonal().array() += 1e-3 * C.trace();
      Eigen::Map<Eigen::VectorXd>(&W[i * k], k) = C.ldlt().solve(Eigen::VectorXd::Ones(k));
    }
  });
  report("optimal_weights", seconds_since(t0));

  t0 = std::chrono::steady_clock::now();
  {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(n * (k + 1));
    for (std::size_t i = 0; i < n; ++i) {
      t.emplace_back(i, i, 1.0);
      for (int j = 0; j < k; ++j) t.emplace_back(i, nb(i, j), -W[i * k + j]);
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> L(n, n);
    L.setFromTriplets(t.begin(), t.end());
    if (L.nonZeros() == 0) std::printf("empty\n");
  }
  report("sparse_assembly", seconds_since(t0));
  std::printf("floor %-16s %8.3f\n", "sum", sum);
  return 0;
}
