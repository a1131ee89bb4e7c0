#include "nodes/post/link.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/point_text.h"
#include "nodes/path/gouge_guard.h"
#include "nodes/path/step_size.h"
#include "nodes/post/centre_index.h"

namespace scallop {
namespace {

using XY = PointsAdaptor<Eigen::Vector3d>;  // searched by xy
using Tree = KdTree<Eigen::Vector3d, 2>;

double seg_dist_xy(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Vector2d e = (b - a).head<2>(), w = (q - a).head<2>();
  double ee = e.squaredNorm();
  double t = ee > 0 ? std::clamp(w.dot(e) / ee, 0.0, 1.0) : 0.0;
  return (w - t * e).norm();
}

}  // namespace

double largest_stepover(const Toolpath& path) {
  double best = 0;
  const ToolpathPass* prev = nullptr;
  for (const auto& p : path.passes) {
    if (p.contact.empty()) continue;
    if (prev) {
      const Eigen::Vector3d& m = p.contact[p.contact.size() / 2];
      double d = INFINITY;
      for (const auto& q : prev->contact) d = std::min(d, (q - m).norm());
      best = std::max(best, d);
    }
    prev = &p;
  }
  return best;
}

LinkedPath link_passes(const Toolpath& path, const std::vector<Eigen::Vector3d>& surface_in,
                       const LinkOptions& o, const BallClearance* clearance) {
  path.check_passes();
  const double r = path.tool_radius;
  std::vector<Eigen::Vector3d> own;
  if (surface_in.empty())
    for (const auto& p : path.passes) own.insert(own.end(), p.contact.begin(), p.contact.end());
  const std::vector<Eigen::Vector3d>& surface = surface_in.empty() ? own : surface_in;

  const double tol = o.tolerance > 0 ? o.tolerance : std::max(path.chord_error, 1e-3);
  const double max_link = o.max_link > 0 ? o.max_link : 2 * largest_stepover(path);
  double top = -INFINITY, bottom = INFINITY;
  for (const auto& q : surface) {
    if (!q.allFinite()) throw std::invalid_argument("the surface has a non-finite point");
    top = std::max(top, q.z());
    bottom = std::min(bottom, q.z());
  }
  // (the points not machined too: a wall the trim left out beside the patch may stand higher)
  if (clearance)
    for (const auto& q : clearance->left_out()) top = std::max(top, q.z());
  const double part_top = top;
  Eigen::Vector3d highest = Eigen::Vector3d::Constant(-INFINITY);
  for (const auto& p : path.passes)
    for (const auto& c : p.contact)
      if (c.z() > highest.z()) highest = c;
  top = std::max(top, highest.z());
  // Passes far above the part do not follow its surface (a guard lift at a fold-over of the map,
  // say): a clearance plane raised to them is not a result.
  const double limit = 10 * r + (part_top - bottom);
  if (highest.z() - part_top > limit)
    throw std::runtime_error("the passes rise to z " + short_number(highest.z()) + " near x " + short_number(highest.x()) + ", y " +
                             short_number(highest.y()) + ", " + short_number(highest.z() - part_top) + " mm above the part's top (z " +
                             short_number(part_top) + "): more than 10 tool radii + the part's height range (" + short_number(limit) +
                             " mm), so the clearance plane would be at z " + short_number(highest.z() + o.safety) +
                             "; the passes do not follow the surface there (e.g. a gouge guard lift at a "
                             "fold-over of the (u,v) map)");

  // A straight move of the ball centre from a to b is safe when no surface point within r of it
  // in xy is nearer than r − tol to the centre segment. With link_clear the points are not
  // searched: it checks the whole part, which holds them (a part's vertices lie on its faces;
  // post.setup_programs' distance holds the cloud's points outside them), and the columns of
  // points under a link in xy were a tenth of the block's programs node.
  // (the clearance check's own tree when it searches the same points)
  std::unique_ptr<XY> adaptor;
  std::unique_ptr<Tree> own_tree;
  const Tree* tree = nullptr;
  if (clearance && &clearance->points() == &surface) {
    tree = &clearance->xy_tree();
  } else if (!o.link_clear || !o.drop) {
    adaptor = std::make_unique<XY>(XY{surface});
    own_tree = std::make_unique<Tree>(2, *adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    own_tree->buildIndex();
    tree = own_tree.get();
  }
  auto safe = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    if (o.link_clear) {
      if (!o.link_clear(a, b)) return false;
    } else {
      Eigen::Vector3d mid = 0.5 * (a + b);
      double R = 0.5 * (b - a).head<2>().norm() + r;
      std::vector<std::pair<std::uint32_t, double>> hits;
      tree->radiusSearch(mid.data(), R * R, hits, nanoflann::SearchParams(32, 0, false));
      for (const auto& [i, d2] : hits) {
        const Eigen::Vector3d& q = surface[i];
        if (seg_dist_xy(q, a, b) > r) continue;
        if (segment_distance(q, a, b) < r - tol) return false;
      }
    }
    if (!clearance) return true;
    // The ball every quarter of the cloud spacing along the link (at most r / 16).
    const double step = std::min(0.25 * clearance->spacing(), r / 16);
    const int m = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int i = 0; i <= m; ++i) {
      const Eigen::Vector3d c = a + (b - a) * (double(i) / m);
      const BallClearance::Result res = (*clearance)(c, c - Eigen::Vector3d(0, 0, r));
      const double u = res.on_surface ? res.uncertainty : 0.0;
      if (res.reach() > tol - kUncertaintyRoughness * u) return false;
    }
    return true;
  };

  LinkedPath out;
  out.tool_radius = r;
  out.scallop_height = path.scallop_height;
  out.chord_error = path.chord_error;
  out.clearance_z = top + o.safety;
  auto& mv = out.moves;
  // The tip's height above a pass start or end where the rapids stop: where a ball of
  // r + lead_height coming down that column first touches the part (a ball of r there keeps
  // lead_height off it), at least lead_height above the tip. A rapid down beside a wall would
  // otherwise graze it, and a finish's stock on it.
  auto rapid_stop = [&](const Eigen::Vector3d& tip) {
    const double R = r + o.lead_height;
    const Eigen::Vector3d high(tip.x(), tip.y(), out.clearance_z + r);
    double centre_z = -INFINITY;
    if (o.drop) {
      centre_z = high.z() - o.drop(high, R, std::max(0.0, out.clearance_z - tip.z()));
    } else {
      std::vector<std::pair<std::uint32_t, double>> hits;
      tree->radiusSearch(high.data(), R * R, hits, nanoflann::SearchParams(32, 0, false));
      for (const auto& [i, d2] : hits) centre_z = std::max(centre_z, surface[i].z() + std::sqrt(R * R - d2));
    }
    return std::min(out.clearance_z, std::max(tip.z() + o.lead_height, centre_z - r));
  };
  // Down at rapid rate to there, the rest at plunge rate (a plunge from the clearance plane was
  // 42 % of the fandisk's programs' feed length); up at feed rate to there, then the rapid.
  auto come_down = [&](const Eigen::Vector3d& tip) {
    mv.push_back({MoveKind::Rapid, {tip.x(), tip.y(), out.clearance_z}});
    const double stop = rapid_stop(tip);
    if (stop < out.clearance_z) mv.push_back({MoveKind::Rapid, {tip.x(), tip.y(), stop}});
    mv.push_back({MoveKind::Plunge, tip});
  };
  auto go_up = [&](const Eigen::Vector3d& tip) {
    const double stop = rapid_stop(tip);
    if (stop < out.clearance_z) mv.push_back({MoveKind::Feed, {tip.x(), tip.y(), stop}});
    mv.push_back({MoveKind::Rapid, {tip.x(), tip.y(), out.clearance_z}});
  };

  // Whether each pass is joined to the one before it by a straight feed. Each pair is decided
  // alone, so the pairs are checked side by side (at a million points the links' ball checks
  // held one core for half a second); a part's own link_clear is called from one thread.
  std::vector<const ToolpathPass*> cut;
  for (const auto& p : path.passes)
    if (!p.contact.empty()) cut.push_back(&p);
  std::vector<std::uint8_t> joined(cut.size(), 0);
  auto decide = [&](std::size_t j) {
    const Eigen::Vector3d from = path.centre(cut[j - 1]->contact.back(), cut[j - 1]->normal.back());
    const Eigen::Vector3d to = path.centre(cut[j]->contact.front(), cut[j]->normal.front());
    joined[j] = (to - from).norm() <= max_link && safe(from, to);
  };
  if (o.link_clear) {
    for (std::size_t j = 1; j < cut.size(); ++j) decide(j);
  } else if (cut.size() > 1) {
    tbb::parallel_for(std::size_t(1), cut.size(), decide);
  }

  for (std::size_t j = 0; j < cut.size(); ++j) {
    const ToolpathPass& p = *cut[j];
    const Eigen::Vector3d t0 = path.tip(p.contact[0], p.normal[0]);
    if (j == 0) {
      come_down(t0);
    } else if (joined[j]) {
      mv.push_back({MoveKind::Feed, t0});
    } else {
      go_up(path.tip(cut[j - 1]->contact.back(), cut[j - 1]->normal.back()));
      come_down(t0);
    }
    for (std::size_t i = 1; i < p.contact.size(); ++i) mv.push_back({MoveKind::Feed, path.tip(p.contact[i], p.normal[i])});
  }
  if (!cut.empty()) go_up(path.tip(cut.back()->contact.back(), cut.back()->normal.back()));
  return out;
}

}  // namespace scallop
