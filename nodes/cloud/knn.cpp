#include "nodes/cloud/knn.h"
#include "engine/parallel_progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include "nodes/geom/kd_tree.h"

namespace scallop {

namespace {

// nanoflann reads the points in place: no copy of the cloud.
using CloudAdaptor = PointsAdaptor<Eigen::Vector3d>;
using Tree = KdTree<Eigen::Vector3d, 3>;

// The next double above a finite d >= 0 (std::nextafter, without the library call): a result
// set's worstDist() one ulp above its bound lets points at the bound itself in.
double next_up(double d) { return std::bit_cast<double>(std::bit_cast<std::uint64_t>(d) + 1); }

// A k-best result set ordered by (distance, index), which skips one index (the query point
// itself). nanoflann's own KNNResultSet orders only by distance and rejects a candidate whose
// distance equals the current worst, so equal distances would come out in tree order; reporting
// worstDist() one ulp above the k-th distance lets equal-distance candidates reach addPoint(),
// which then keeps the lowest indices. This makes the result independent of the tree layout.
// The k best are kept as a max-heap (the worst on top) and sorted by finish(): an insertion into
// a sorted array moves O(k) entries, and at the denoiser's k of 300 to 1200 that was most of its
// time (58 % of cloud.denoise's samples on a 50 000-point cloud, k = 300).
class OrderedKnnResult {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  OrderedKnnResult(int k, std::int64_t skip, int* idx, double* dist)
      : k_(static_cast<std::size_t>(k)), skip_(skip), idx_(idx), dist_(dist) {}

  std::size_t size() const { return count_; }
  bool full() const { return count_ == k_; }

  bool addPoint(double d, IndexType index) {
    if (static_cast<std::int64_t>(index) == skip_) return true;
    const int i_new = static_cast<int>(index);
    if (!full()) {
      dist_[count_] = d;
      idx_[count_] = i_new;
      if (++count_ == k_) {
        for (std::size_t i = k_ / 2; i-- > 0;) sift_down(i, k_);
        worst_ = next_up(dist_[0]);  // cached: the tree asks at every node it visits
      }
      return true;
    }
    if (!before(d, i_new, dist_[0], idx_[0])) return true;
    dist_[0] = d;
    idx_[0] = i_new;
    sift_down(0, k_);
    worst_ = next_up(dist_[0]);
    return true;
  }

  double worstDist() const { return worst_; }
  // The squared distance of the farthest point found (the k-th when full; 0 when none).
  double farthest() const {
    if (full()) return dist_[0];
    double d = 0;
    for (std::size_t i = 0; i < count_; ++i) d = std::max(d, dist_[i]);
    return d;
  }

  // Puts the points found in order, nearest first (call once, after the search).
  void finish() {
    thread_local std::vector<std::pair<double, int>> found;
    found.resize(count_);
    for (std::size_t i = 0; i < count_; ++i) found[i] = {dist_[i], idx_[i]};
    std::sort(found.begin(), found.end());  // (distance, index): the order before() gives
    for (std::size_t i = 0; i < count_; ++i) {
      dist_[i] = found[i].first;
      idx_[i] = found[i].second;
    }
  }

 private:
  static bool before(double d1, int i1, double d2, int i2) {
    return d1 < d2 || (d1 == d2 && i1 < i2);
  }
  // Restores the max-heap below entry i of the first n.
  void sift_down(std::size_t i, std::size_t n) {
    const double d = dist_[i];
    const int id = idx_[i];
    for (;;) {
      std::size_t c = 2 * i + 1;
      if (c >= n) break;
      if (c + 1 < n && before(dist_[c], idx_[c], dist_[c + 1], idx_[c + 1])) ++c;
      if (!before(d, id, dist_[c], idx_[c])) break;
      dist_[i] = dist_[c];
      idx_[i] = idx_[c];
      i = c;
    }
    dist_[i] = d;
    idx_[i] = id;
  }
  std::size_t k_;
  std::int64_t skip_;
  int* idx_;
  double* dist_;
  std::size_t count_ = 0;
  double worst_ = std::numeric_limits<double>::max();
};

// Every point within a squared distance (inclusive), but one skipped index, in no order.
class WithinResult {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  WithinResult(double sq_radius, std::int64_t skip, std::vector<std::pair<double, int>>& found)
      : worst_(next_up(sq_radius)), skip_(skip), found_(found) {}
  std::size_t size() const { return found_.size(); }
  bool full() const { return true; }
  bool addPoint(double d, IndexType index) {
    if (static_cast<std::int64_t>(index) != skip_) found_.emplace_back(d, static_cast<int>(index));
    return true;
  }
  double worstDist() const { return worst_; }

 private:
  double worst_;  // next_up(the radius): the tree takes only what is nearer than this
  std::int64_t skip_;
  std::vector<std::pair<double, int>>& found_;
};

// Every point of the tree (but `skip`) within squared distance sq_radius of q, in no order, as
// (squared distance, index) in a vector of the calling thread's, kept until its next call.
std::vector<std::pair<double, int>>& points_within(const Tree& tree, const Eigen::Vector3d& q, double sq_radius,
                                                   int skip) {
  thread_local std::vector<std::pair<double, int>> found;
  found.clear();
  WithinResult result(sq_radius, skip, found);
  tree.findNeighbors(result, q.data(), nanoflann::SearchParams());
  return found;
}

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
  result.finish();
}

void KnnIndex::query_within(const Eigen::Vector3d& q, double sq_radius, int k, std::vector<int>& idx,
                            std::vector<double>& sq_dist, int skip, bool in_order) const {
  std::vector<std::pair<double, int>>& found = points_within(impl_->tree, q, sq_radius, skip);
  const std::size_t want = std::min<std::size_t>(std::max(k, 0), found.size());
  // by (distance, index); more than k only where distances tie at the radius
  if (want < found.size()) std::nth_element(found.begin(), found.begin() + want, found.end());
  if (in_order) std::sort(found.begin(), found.begin() + want);
  idx.resize(want);
  sq_dist.resize(want);
  for (std::size_t i = 0; i < want; ++i) {
    sq_dist[i] = found[i].first;
    idx[i] = found[i].second;
  }
}

double KnnIndex::kth_sq_distance(const Eigen::Vector3d& q, int k, int skip, double guess) const {
  const std::size_t available = size() - (skip >= 0 && static_cast<std::size_t>(skip) < size());
  const int want = static_cast<int>(std::min<std::size_t>(std::max(k, 0), available));
  if (want == 0) return 0;
  if (guess > 0) {
    // Every point within the guess: when there are k or more, the k-th of them by (distance,
    // index) is the k-th of all. A search of known radius prunes from the start and keeps no order.
    std::vector<std::pair<double, int>>& found = points_within(impl_->tree, q, guess, skip);
    if (found.size() >= static_cast<std::size_t>(want)) {
      std::nth_element(found.begin(), found.begin() + (want - 1), found.end());
      return found[want - 1].first;
    }
  }
  thread_local std::vector<int> idx;
  thread_local std::vector<double> sq_dist;
  idx.resize(want);
  sq_dist.resize(want);
  OrderedKnnResult result(want, skip, idx.data(), sq_dist.data());
  impl_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams());
  return result.farthest();
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
                        result.finish();
                      }
                      done.done(r.size());
                    });
  return out;
}

}  // namespace scallop
