// nanoflann vs PCL (FLANN) k-d trees for the all-points KNN that cloud.knn computes.
//
// Standalone Google Benchmark program; PCL headers live only here, never in the product.
// Input: a binary little-endian PLY of float x y z, by default /tmp/waves1m.ply made with
//   /usr/bin/python3 ../shared/tools/make_cloud.py --surface waves --n 1000000 --seed 1 -o /tmp/waves1m.ply
// (or set SCALLOP_KNN_BENCH_PLY; SCALLOP_BENCH_THREADS=n caps oneTBB's threads). k = 12, the
// point itself excluded. Builds are single-threaded in both libraries (neither nanoflann 1.4 nor
// FLANN's single k-d tree builds in parallel); queries run under tbb::parallel_for in both.
//
// Benchmarks: <backend>/build, <backend>/query/{0,1} (tree built once outside the timing;
// queries in index order / in a spatially coherent order), <backend>/total (build + queries in
// index order), and product/compute_knn (the product function: nanoflann, queries in leaf
// order, ties ordered by index).
//
// Measured on the shared 2-core dev machine (load ~6, so real times are inflated by
// other jobs; process CPU time of all threads is the steadier figure), median of 3, CPU time,
// SCALLOP_BENCH_THREADS=1:
//   nanoflann        build 460 ms   query 5000 ms (index order) / 1290 ms (leaf order)
//   PCL KdTreeFLANN  build 297 ms   query 3540 ms (index order) / 1900 ms (leaf order)
//   totals: nanoflann 5690 ms, PCL 4070 ms (index order); product/compute_knn 1790 ms
// With 2 threads (CPU of all threads / real): product 1890 / 3730 ms, PCL total 4030 / 8640 ms.
// Query order dominates (the cloud is stored in random order); with the same coherent order
// nanoflann queries faster than FLANN and its tree hands the order out for free, so the
// product keeps nanoflann.
#include <benchmark/benchmark.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <nanoflann.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "nodes/cloud/knn.h"

namespace {

constexpr int kK = 12;

std::vector<Eigen::Vector3d> read_xyz_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::string line;
  std::size_t n = 0;
  int props = 0;
  bool binary = false;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream ls(line);
    std::string w, a, b;
    ls >> w >> a >> b;
    if (w == "format") binary = (a == "binary_little_endian");
    if (w == "element" && a == "vertex") n = std::stoull(b);
    if (w == "property") {
      if (a != "float") throw std::runtime_error("bench reader wants float x y z only");
      ++props;
    }
  }
  if (!binary || props != 3) throw std::runtime_error("bench reader wants binary LE float x y z");
  std::vector<float> raw(3 * n);
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size() * 4));
  if (!in) throw std::runtime_error("truncated " + path);
  std::vector<Eigen::Vector3d> P(n);
  for (std::size_t i = 0; i < n; ++i) P[i] = {raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]};
  return P;
}

const std::vector<Eigen::Vector3d>& cloud() {
  static const std::vector<Eigen::Vector3d> P = [] {
    const char* env = std::getenv("SCALLOP_KNN_BENCH_PLY");
    return read_xyz_ply(env ? env : "/tmp/waves1m.ply");
  }();
  return P;
}

// ---- nanoflann, over the double points in place (as the product does) ----
struct Adaptor {
  const std::vector<Eigen::Vector3d>& P;
  std::size_t kdtree_get_point_count() const { return P.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return P[i][static_cast<int>(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const { return false; }
};
using NanoTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3,
                                        std::uint32_t>;

// Query order: index order (as stored) or a spatially coherent order (the leaf order of a
// nanoflann tree, computed outside the timing), to separate the trees from cache effects.
const std::vector<std::uint32_t>& leaf_order();

std::size_t pick(const std::vector<std::uint32_t>* order, std::size_t q) {
  return order ? (*order)[q] : q;
}

void nano_query(const NanoTree& tree, const std::vector<Eigen::Vector3d>& P,
                std::vector<int>& idx, std::vector<double>& dist,
                const std::vector<std::uint32_t>* order = nullptr) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 1024), [&](const auto& r) {
    std::uint32_t ii[kK + 1];
    double dd[kK + 1];
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const std::size_t i = pick(order, q);
      nanoflann::KNNResultSet<double, std::uint32_t> rs(kK + 1);
      rs.init(ii, dd);
      tree.findNeighbors(rs, P[i].data(), nanoflann::SearchParams());
      for (int j = 0, o = 0; j <= kK && o < kK; ++j)  // drop the point itself
        if (ii[j] != i) {
          idx[i * kK + o] = static_cast<int>(ii[j]);
          dist[i * kK + o++] = dd[j];
        }
    }
  });
}

void BM_nanoflann_build(benchmark::State& st) {
  const auto& P = cloud();
  Adaptor a{P};
  for (auto _ : st) {
    NanoTree tree(3, a, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    auto* escape = &tree;
    benchmark::DoNotOptimize(escape);
    benchmark::ClobberMemory();
  }
}

void BM_nanoflann_query(benchmark::State& st) {
  const auto& P = cloud();
  Adaptor a{P};
  NanoTree tree(3, a, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();
  std::vector<int> idx(P.size() * kK);
  std::vector<double> dist(P.size() * kK);
  const auto* order = st.range(0) ? &leaf_order() : nullptr;
  for (auto _ : st) nano_query(tree, P, idx, dist, order);
}

const std::vector<std::uint32_t>& leaf_order() {
  static const std::vector<std::uint32_t> order = [] {
    Adaptor a{cloud()};
    NanoTree tree(3, a, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    return tree.vAcc;
  }();
  return order;
}

void BM_nanoflann_total(benchmark::State& st) {
  const auto& P = cloud();
  Adaptor a{P};
  std::vector<int> idx(P.size() * kK);
  std::vector<double> dist(P.size() * kK);
  for (auto _ : st) {
    NanoTree tree(3, a, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    nano_query(tree, P, idx, dist);
  }
}

// ---- PCL: KdTreeFLANN over a float PointXYZ copy (its native form; the copy is not timed) ----
pcl::PointCloud<pcl::PointXYZ>::Ptr pcl_cloud() {
  static const auto C = [] {
    auto c = pcl::PointCloud<pcl::PointXYZ>::Ptr(new pcl::PointCloud<pcl::PointXYZ>);
    for (const auto& p : cloud()) c->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
    return c;
  }();
  return C;
}

void pcl_query(const pcl::KdTreeFLANN<pcl::PointXYZ>& tree, std::size_t n, std::vector<int>& idx,
               std::vector<float>& dist, const std::vector<std::uint32_t>* order = nullptr) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    std::vector<int> ii(kK + 1);
    std::vector<float> dd(kK + 1);
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const std::size_t i = pick(order, q);
      tree.nearestKSearch(static_cast<pcl::index_t>(i), kK + 1, ii, dd);
      for (int j = 0, o = 0; j <= kK && o < kK; ++j)
        if (ii[j] != static_cast<int>(i)) {
          idx[i * kK + o] = ii[j];
          dist[i * kK + o++] = dd[j];
        }
    }
  });
}

void BM_pcl_build(benchmark::State& st) {
  auto C = pcl_cloud();
  for (auto _ : st) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(C);
    auto* escape = &tree;
    benchmark::DoNotOptimize(escape);
    benchmark::ClobberMemory();
  }
}

void BM_pcl_query(benchmark::State& st) {
  auto C = pcl_cloud();
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(C);
  std::vector<int> idx(C->size() * kK);
  std::vector<float> dist(C->size() * kK);
  const auto* order = st.range(0) ? &leaf_order() : nullptr;
  for (auto _ : st) pcl_query(tree, C->size(), idx, dist, order);
}

void BM_pcl_total(benchmark::State& st) {
  auto C = pcl_cloud();
  std::vector<int> idx(C->size() * kK);
  std::vector<float> dist(C->size() * kK);
  for (auto _ : st) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(C);
    pcl_query(tree, C->size(), idx, dist);
  }
}

// ---- the product function (nanoflann, ordered ties, self excluded by index) ----
void BM_product_compute_knn(benchmark::State& st) {
  const auto& P = cloud();
  for (auto _ : st) {
    scallop::Neighborhoods nb = scallop::compute_knn(P, kK);
    benchmark::DoNotOptimize(nb.indices.data());
  }
}

}  // namespace

// Real time and the CPU time of all threads; query/0 = index order, query/1 = leaf order.
#define SCALLOP_KNN_BENCH(fn, name) \
  BENCHMARK(fn)->Name(name)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()
SCALLOP_KNN_BENCH(BM_nanoflann_build, "nanoflann/build");
SCALLOP_KNN_BENCH(BM_nanoflann_query, "nanoflann/query")->Arg(0)->Arg(1);
SCALLOP_KNN_BENCH(BM_nanoflann_total, "nanoflann/total");
SCALLOP_KNN_BENCH(BM_pcl_build, "pcl_kdtree_flann/build");
SCALLOP_KNN_BENCH(BM_pcl_query, "pcl_kdtree_flann/query")->Arg(0)->Arg(1);
SCALLOP_KNN_BENCH(BM_pcl_total, "pcl_kdtree_flann/total");
SCALLOP_KNN_BENCH(BM_product_compute_knn, "product/compute_knn");

// SCALLOP_BENCH_THREADS=n caps oneTBB's parallelism (1: per-core cost on a busy machine).
int main(int argc, char** argv) {
  std::unique_ptr<tbb::global_control> limit;
  if (const char* t = std::getenv("SCALLOP_BENCH_THREADS"))
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(std::atoi(t)));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
