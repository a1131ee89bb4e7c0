#include "nodes/post/centre_index.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scallop {

double centre_piece_length(const std::vector<CentreSegment>& feed, double spacing, double r) {
  std::vector<double> lengths;
  lengths.reserve(feed.size());
  for (const auto& s : feed) lengths.push_back((s.b - s.a).norm());
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() * 9 / 10, lengths.end());
  return std::clamp(lengths[lengths.size() * 9 / 10], spacing, std::max(spacing, r / 2));
}

// The capsule is the union of a finite cylinder and two balls; the flat ends of the cylinder lie
// inside the balls, so the first entry is the least of the side entry (when its foot falls on
// the segment) and the two ball entries.
double capsule_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, double r) {
  double best = INFINITY;
  auto ball = [&](const Eigen::Vector3d& c) {
    Eigen::Vector3d oc = o - c;
    double bb = oc.dot(d), cc = oc.squaredNorm() - r * r;
    double disc = bb * bb - cc;
    if (disc < 0) return;
    double t = -bb - std::sqrt(disc);
    if (t >= 0) best = std::min(best, t);
  };
  ball(a);
  ball(b);
  Eigen::Vector3d e = b - a;
  double ee = e.squaredNorm();
  if (ee > 0) {
    Eigen::Vector3d w = o - a;
    double ed = e.dot(d), ew = e.dot(w);
    // |w + t d − ((ew + t ed)/ee) e|² = r²  →  A t² + 2 B t + C = 0
    double A = ee - ed * ed, B = ee * w.dot(d) - ew * ed, C = ee * w.squaredNorm() - ew * ew - r * r * ee;
    if (A > 1e-12 * ee) {
      double disc = B * B - A * C;
      if (disc >= 0) {
        double s = std::sqrt(disc);
        double t = B > 0 ? (-B - s) / A : C / (-B + s);  // the smaller root, without cancellation
        if (t >= 0) {
          double f = ew + t * ed;
          if (f >= 0 && f <= ee) best = std::min(best, t);
        }
      }
    }
  }
  return best;
}

CentreIndex::CentreIndex(const std::vector<CentreSegment>& segs, double piece) {
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const CentreSegment& s = segs[i];
    double L = (s.b - s.a).norm();
    int k = std::max(1, static_cast<int>(std::ceil(L / piece)));
    for (int j = 0; j < k; ++j) {
      a_.push_back(s.a + (s.b - s.a) * (double(j) / k));
      b_.push_back(s.a + (s.b - s.a) * (double(j + 1) / k));
      mid_.push_back(0.5 * (a_.back() + b_.back()));
      owner_.push_back(static_cast<std::uint32_t>(i));
      half_ = std::max(half_, 0.5 * L / k);
    }
  }
  adaptor_ = std::make_unique<PointsAdaptor<Eigen::Vector3d>>(PointsAdaptor<Eigen::Vector3d>{mid_});
  if (mid_.empty()) return;
  tree_ = std::make_unique<KdTree<Eigen::Vector3d, 3>>(3, *adaptor_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree_->buildIndex();
}

void CentreIndex::near(const Eigen::Vector3d& m, double radius, std::vector<std::uint32_t>& out) const {
  CollectWithin rs{radius * radius, &out};
  out.clear();
  if (!a_.empty()) tree_->findNeighbors(rs, m.data(), nanoflann::SearchParams(32, 0, false));
}

void CentreIndex::near(const Eigen::Vector3d& m, double radius, std::vector<std::uint32_t>& out,
                       CandidateCache* cache) const {
  if (!cache || !(cache->slack > 0)) return near(m, radius, out);
  constexpr double kSpare = 1e-9;  // mm, beyond the rounding of the distances compared
  if (!((m - cache->centre).norm() + radius + kSpare <= cache->radius)) {
    near(m, radius + cache->slack, cache->pieces);
    cache->centre = m, cache->radius = radius + cache->slack;
  }
  // The tree's own test (CollectWithin): its squared distance below the radius squared.
  const double r2 = radius * radius;
  out.clear();
  for (std::uint32_t i : cache->pieces)
    if (tree_distance2(m, mid_[i]) < r2) out.push_back(i);
}

double CentreIndex::distance(const Eigen::Vector3d& p, double cap, std::vector<std::uint32_t>& cand) const {
  near(p, cap + half_, cand);
  double d = INFINITY;
  for (auto i : cand) d = std::min(d, segment_distance(p, a_[i], b_[i]));
  return d < cap ? d : INFINITY;
}

std::uint32_t CentreIndex::nearest(const Eigen::Vector3d& p, double cap, std::vector<std::uint32_t>& cand) const {
  near(p, cap + half_, cand);
  double d = cap;
  std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
  for (auto i : cand)
    if (const double di = segment_distance(p, a_[i], b_[i]); di < d) d = di, best = i;
  return best;
}

void CentreIndex::trace(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double r, double T, double delta,
                        double& gouge, double& scallop, std::vector<std::uint32_t>& cand, std::uint32_t* hint,
                        CandidateCache* cache) const {
  // With a hint whose capsule the ray enters at t_h <= T/2 (or whose centre is within r of p),
  // every piece that matters lies within r + max(t_h, delta) (r + delta) of p, so its midpoint
  // within that plus half a piece: the pieces entered sooner, and those near enough for the
  // gouge. Otherwise every piece that can come within r of the ray [p, p + T n].
  bool narrowed = false;
  if (hint && *hint < a_.size()) {
    constexpr double kSpare = 1e-9;  // rounding of the distances compared
    if (segment_distance(p, a_[*hint], b_[*hint]) <= r) {
      near(p, r + delta + half_ + kSpare, cand, cache);
      narrowed = true;
    } else if (const double th = capsule_entry(p, n, a_[*hint], b_[*hint], r); th <= 0.5 * T) {
      near(p, r + std::max(th, delta) + half_ + kSpare, cand, cache);
      narrowed = true;
    }
  }
  if (!narrowed || cand.empty()) near(p + 0.5 * T * n, r + 0.5 * T + half_, cand, cache);
  thread_local std::vector<double> dist;  // to each candidate
  dist.resize(cand.size());
  double d = INFINITY;
  std::size_t nearest = 0;
  for (std::size_t c = 0; c < cand.size(); ++c) {
    dist[c] = segment_distance(p, a_[cand[c]], b_[cand[c]]);
    if (dist[c] < d) d = dist[c], nearest = c;
  }
  gouge = std::max(0.0, r - d + delta);
  if (d <= r) {
    scallop = std::max(0.0, delta - (r - d));
    if (hint) *hint = cand[nearest];
    return;
  }
  // The ray enters a piece's capsule no sooner than (its distance from p) − r, the distance
  // changing no faster than the ray moves: starting from the nearest piece, the pieces that
  // cannot come first are skipped (with a nanometre to spare for rounding; the least entry, and
  // so the scallop, is the same as over every piece).
  double t = cand.empty() ? INFINITY : capsule_entry(p, n, a_[cand[nearest]], b_[cand[nearest]], r);
  std::size_t first = nearest;
  for (std::size_t c = 0; c < cand.size(); ++c)
    if (dist[c] - r <= t + 1e-6)
      if (const double tc = capsule_entry(p, n, a_[cand[c]], b_[cand[c]], r); tc < t) t = tc, first = c;
  scallop = t <= T ? t + delta : std::numeric_limits<double>::quiet_NaN();
  if (hint) *hint = cand.empty() ? std::numeric_limits<std::uint32_t>::max() : cand[first];
}

WeightedStats weighted_stats(std::vector<std::pair<double, double>> vw) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  WeightedStats s{kNaN, kNaN, kNaN};
  if (vw.empty()) return s;
  tbb::parallel_sort(vw.begin(), vw.end());
  double total = 0, sum = 0;
  for (auto& [v, w] : vw) total += w, sum += v * w;
  s.max = vw.back().first;
  s.mean = total > 0 ? sum / total : kNaN;
  double acc = 0;
  s.p99 = vw.back().first;
  for (auto& [v, w] : vw) {
    acc += w;
    if (acc / total >= 0.99) {
      s.p99 = v;
      break;
    }
  }
  return s;
}

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

void report_scallop(nlohmann::json& rep, double max_all, double max_interior, const WeightedStats& all,
                    const WeightedStats& interior) {
  rep["scallop_max"] = finite_or_null(max_all);
  rep["scallop_max_interior"] = finite_or_null(max_interior);
  rep["scallop_p99"] = finite_or_null(all.p99);
  rep["scallop_p99_interior"] = finite_or_null(interior.p99);
  rep["scallop_mean"] = finite_or_null(all.mean);
  rep["scallop_mean_interior"] = finite_or_null(interior.mean);
}

}  // namespace scallop
