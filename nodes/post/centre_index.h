// The ball-centre polyline of a cut, indexed for the questions a cutting simulation asks of it:
// how far a point is from the nearest centre (the gouge) and where a ray from the surface first
// comes within the tool radius of one (the scallop). post.simulate asks it of one patch,
// post.simulate_part of a whole part and all its setups.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "nodes/geom/kd_tree.h"
#include "nodes/geom/segment.h"

namespace scallop {

// One straight piece of the ball-centre polyline (mm).
struct CentreSegment {
  Eigen::Vector3d a, b;
};

// First t >= 0 at which the ray o + t·d (|d| = 1) is within r of the segment [a, b]; +inf if
// never (the ray starts outside that capsule).
double capsule_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, double r);

// The segments cut into pieces no longer than `piece`, with a k-d tree over their midpoints.
class CentreIndex {
 public:
  CentreIndex(const std::vector<CentreSegment>& segments, double piece);
  bool empty() const { return a_.empty(); }
  // The distance from p to the nearest piece when it is below `cap`, else +infinity.
  double distance(const Eigen::Vector3d& p, double cap, std::vector<std::uint32_t>& scratch) const;
  // gouge and scallop (NaN: uncut) at p with unit normal n, where the real surface may lie up to
  // `delta` off p either way: the gouge is then at most r - d(p) + delta, the scallop at most its
  // value at p plus delta (the ray from p - delta n reaches p after delta); uncut when the ray
  // [p, p + T n] never comes within r of a piece. Every piece that comes within r of that ray
  // segment has its midpoint within r + T/2 + half a piece of the ray's middle, so the candidates
  // are complete and, for delta = 0, both values exact.
  // hint, when given, is a piece to start from (UINT32_MAX: none), set on return to the piece
  // the answer came from: for the next of a row of nearby points, whose ray enters that piece
  // early, a search only as wide as that entry needs (the same answer, fewer candidates).
  //
  // cache, when given, keeps the pieces of a search made `slack` wider than asked; the next
  // searches it contains (a row's next places, a slack apart or less) pick theirs from it by the
  // same distance test the tree makes: the same candidates, without a descent of the tree.
  struct CandidateCache {
    double slack = 0;  // mm
    Eigen::Vector3d centre = Eigen::Vector3d::Constant(NAN);
    double radius = -1;
    std::vector<std::uint32_t> pieces;
  };
  void trace(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double r, double T, double delta, double& gouge,
             double& scallop, std::vector<std::uint32_t>& scratch, std::uint32_t* hint = nullptr,
             CandidateCache* cache = nullptr) const;
  // The index of the segment (given to the constructor) a piece came from.
  std::uint32_t segment_of(std::uint32_t piece) const { return owner_[piece]; }
  // The piece nearest to p within `cap` (UINT32_MAX when none).
  std::uint32_t nearest(const Eigen::Vector3d& p, double cap, std::vector<std::uint32_t>& scratch) const;

 private:
  void near(const Eigen::Vector3d& m, double radius, std::vector<std::uint32_t>& out) const;
  void near(const Eigen::Vector3d& m, double radius, std::vector<std::uint32_t>& out, CandidateCache* cache) const;
  std::vector<Eigen::Vector3d> a_, b_, mid_;
  std::vector<std::uint32_t> owner_;
  double half_ = 0;
  std::unique_ptr<PointsAdaptor<Eigen::Vector3d>> adaptor_;
  std::unique_ptr<KdTree<Eigen::Vector3d, 3>> tree_;
};

// The piece length a cut's CentreIndex is built with: the 90th percentile of the segments'
// lengths, within [spacing, max(spacing, r / 2)] (the sample spacing, the tool radius). `feed`
// must not be empty.
double centre_piece_length(const std::vector<CentreSegment>& feed, double spacing, double r);

// Area-weighted statistics of (value, weight) pairs: NaN when there is none.
struct WeightedStats {
  double max, p99, mean;
};
WeightedStats weighted_stats(std::vector<std::pair<double, double>> value_weight);

// A number for a report: null when it is not finite.
nlohmann::json finite_or_null(double v);
// The scallop figures of a certificate: scallop_max, _p99, _mean and each _interior (maxima
// given apart: they include the refinement samples, the statistics only the grid's).
void report_scallop(nlohmann::json& report, double max_all, double max_interior, const WeightedStats& all,
                    const WeightedStats& interior);

}  // namespace scallop
