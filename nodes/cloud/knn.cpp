#include "nodes/cloud/knn.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>
#include "nodes/geom/kd_tree.h"

namespace scallop {

namespace {

// nanoflann reads the points in place: no copy of the cloud.
using CloudAdaptor = PointsAdaptor<Eigen::Vector3d>;
using Tree = KdTree<Eigen::Vector3d, 3>;

// A k-best result set ordered by (distance, index), which skips one index (the query point
// itself). nanoflann's own KNNResultSet orders only by distance and rejects a candidate whose
// distance equals the current worst, so equal distances would come out in tree order; reporting
// worstDist() one ulp above the k-th distance lets equal-distance candidates reach addPoint(),
// which then keeps the lowest indices. This makes the result independent of the tree layout.
class OrderedKnnResult {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  OrderedKnnResult(int k, std::int64_t skip, int* idx, double* dist)
      : k_(k), skip_(skip), idx_(idx), dist_(dist) {}

  std::size_t size() const { return count_; }
  bool full() const { return count_ == static_cast<std::size_t>(k_); }

  bool addPoint(double d, IndexType index) {
    if (static_cast<std::int64_t>(index) == skip_) return true;
    const int i_new = static_cast<int>(index);
    if (full() && !before(d, i_new, dist_[k_ - 1], idx_[k_ - 1])) return true;
    std::size_t pos = full() ? count_ - 1 : count_++;
    while (pos > 0 && before(d, i_new, dist_[pos - 1], idx_[pos - 1])) {
      dist_[pos] = dist_[pos - 1];
      idx_[pos] = idx_[pos - 1];
      --pos;
    }
    dist_[pos] = d;
    idx_[pos] = i_new;
    // Cached: the tree asks for worstDist() at every node it visits.
    if (full()) worst_ = next_up(dist_[k_ - 1]);
    return true;
  }

  double worstDist() const { return worst_; }

 private:
  // The next double above a finite d >= 0 (std::nextafter, without the library call).
  static double next_up(double d) {
    return std::bit_cast<double>(std::bit_cast<std::uint64_t>(d) + 1);
  }
  static bool before(double d1, int i1, double d2, int i2) {
    return d1 < d2 || (d1 == d2 && i1 < i2);
  }
  int k_;
  std::int64_t skip_;
  int* idx_;
  double* dist_;
  std::size_t count_ = 0;
  double worst_ = std::numeric_limits<double>::max();
};

void check_points(const std::vector<Eigen::Vector3d>& P) {
  if (P.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::invalid_argument("the cloud has " + std::to_string(P.size()) +
                                " points; at most 2147483646 are supported");
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!P[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a NaN or infinite coordinate");
}

}  // namespace

struct KnnIndex::Impl {
  CloudAdaptor adaptor;
  Tree tree;
  explicit Impl(const std::vector<Eigen::Vector3d>& P)
      : adaptor{P}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    tree.buildIndex();
  }
};

KnnIndex::KnnIndex(const std::vector<Eigen::Vector3d>& P) {
  if (P.empty()) throw std::invalid_argument("the cloud is empty");
  check_points(P);
  impl_ = std::make_unique<Impl>(P);
}

KnnIndex::~KnnIndex() = default;

std::size_t KnnIndex::size() const { return impl_->adaptor.pts.size(); }

void KnnIndex::query(const Eigen::Vector3d& q, int k, std::vector<int>& idx,
                     std::vector<double>& sq_dist, int skip) const {
  const std::size_t available = size() - (skip >= 0 && static_cast<std::size_t>(skip) < size());
  const int want = static_cast<int>(std::min<std::size_t>(std::max(k, 0), available));
  idx.resize(want);
  sq_dist.resize(want);
  if (want == 0) return;
  OrderedKnnResult result(want, skip, idx.data(), sq_dist.data());
  impl_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams());
}

int KnnIndex::nearest(const Eigen::Vector3d& q) const {
  int i = -1;
  double d = 0;
  OrderedKnnResult result(1, -1, &i, &d);
  impl_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams());
  return i;
}

Neighborhoods compute_knn(const std::vector<Eigen::Vector3d>& P, int k,
                          const std::function<void(double)>& progress) {
  if (k < 1) throw std::invalid_argument("k must be at least 1 (got " + std::to_string(k) + ")");
  if (static_cast<std::size_t>(k) >= P.size())
    throw std::invalid_argument("k = " + std::to_string(k) + " needs at least " +
                                std::to_string(k + 1LL) + " points; the cloud has " +
                                std::to_string(P.size()));
  check_points(P);

  CloudAdaptor adaptor{P};
  Tree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();  // nanoflann 1.4 builds single-threaded; the queries dominate anyway

  Neighborhoods out;
  out.k = k;
  out.indices.resize(P.size() * k);
  out.sq_dists.resize(P.size() * k);
  // Queries go in the tree's leaf order (vAcc): consecutive queries then touch the same
  // leaves, which keeps the walk in cache. On a cloud stored in scan or random order this is
  // several times faster than querying in index order.
  const auto& order = tree.vAcc;
  ParallelProgress done(progress, P.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t q = r.begin(); q != r.end(); ++q) {
                        const std::size_t i = order[q];
                        OrderedKnnResult result(k, static_cast<std::int64_t>(i),
                                                &out.indices[i * k], &out.sq_dists[i * k]);
                        tree.findNeighbors(result, P[i].data(), nanoflann::SearchParams());
                      }
                      done.done(r.size());
                    });
  return out;
}

}  // namespace scallop
