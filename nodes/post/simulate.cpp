#include "nodes/post/simulate.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <numeric>
#include <stdexcept>
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/obstacle_points.h"
#include "nodes/post/centre_index.h"
#include "nodes/geom/outline.h"
#include "nodes/post/clearance_march.h"
#include "nodes/post/refinement_seeds.h"
#include "nodes/path/step_size.h"
#include "nodes/geom/point_text.h"
#include "nodes/post/surface_grid.h"

namespace scallop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A trace's search for pieces is made this many grid spacings wider than it asks, and the next
// places of the row pick theirs from what it found (CentreIndex::CandidateCache).
constexpr double kCandidateSlack = 8;



}  // namespace

// ----------------------------------------------------------------------------- path centres
std::vector<CentreSegment> feed_centres(const Toolpath& path) {
  std::vector<CentreSegment> out;
  for (const auto& pass : path.passes) {
    if (pass.normal.size() != pass.contact.size())
      throw std::invalid_argument("a pass has " + std::to_string(pass.contact.size()) + " points but " +
                                  std::to_string(pass.normal.size()) + " normals");
    for (std::size_t i = 0; i + 1 < pass.contact.size(); ++i)
      out.push_back({path.centre(pass.contact[i], pass.normal[i]),
                     path.centre(pass.contact[i + 1], pass.normal[i + 1])});
  }
  return out;
}

std::vector<CentreSegment> feed_centres(const LinkedPath& path, double& rapid_length,
                                        std::vector<CentreSegment>* rapids) {
  std::vector<CentreSegment> out;
  rapid_length = 0;
  if (rapids) rapids->clear();
  const Eigen::Vector3d up(0, 0, path.tool_radius);
  for (std::size_t i = 1; i < path.moves.size(); ++i) {
    const auto& m0 = path.moves[i - 1];
    const auto& m1 = path.moves[i];
    if (m1.kind == MoveKind::Rapid) {
      rapid_length += (m1.tip - m0.tip).norm();
      if (rapids) rapids->push_back({m0.tip + up, m1.tip + up});
    } else {
      out.push_back({m0.tip + up, m1.tip + up});
    }
  }
  return out;
}

namespace {
void check_rapid_inputs(const std::vector<Eigen::Vector3d>& points, double r, double tol) {
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(tol > 0)) throw std::invalid_argument("the rapids' tolerance must be > 0");
  if (points.empty()) throw std::invalid_argument("no points to check the rapids against");
}

// A nanoflann result set for the point nearest a query once each point is raised by its
// uncertainty: a point farther than the nearest raised one found plus the largest raise cannot
// be nearer raised.
struct NearestRaised {
  const Eigen::Vector3d& query;
  const std::vector<Eigen::Vector3d>& points;
  const std::vector<double>& raise;
  double raise_max;
  double best2 = INFINITY;  // the nearest raised point's squared distance
  double reach2 = INFINITY;  // (sqrt(best2) + raise_max)², a little more for rounding
  void init() {}
  std::size_t size() const { return std::isfinite(best2) ? 1 : 0; }
  bool full() const { return true; }
  bool addPoint(double, std::uint32_t i) {
    const Eigen::Vector3d& p = points[i];
    const double d2 = tree_distance2(query, Eigen::Vector3d(p.x(), p.y(), p.z() + raise[i]));
    if (d2 < best2) {
      best2 = d2;
      const double reach = std::sqrt(d2) + raise_max;
      reach2 = reach * reach * (1 + 1e-12);
    }
    return true;
  }
  double worstDist() const { return reach2; }
};
}  // namespace

RapidClearance rapid_clearance(const std::vector<Eigen::Vector3d>& points, const std::vector<double>* uncertainty,
                               const std::vector<CentreSegment>& rapids, double r, double tol) {
  check_rapid_inputs(points, r, tol);
  if (rapids.empty()) return {};
  const PointsAdaptor<Eigen::Vector3d> adaptor{points};
  KdTree<Eigen::Vector3d, 3> tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  return rapid_clearance(points, uncertainty, tree, rapids, r, tol);
}

RapidClearance rapid_clearance(const std::vector<Eigen::Vector3d>& points, const std::vector<double>* uncertainty,
                               const KdTree<Eigen::Vector3d, 3>& tree, const std::vector<CentreSegment>& rapids,
                               double r, double tol) {
  check_rapid_inputs(points, r, tol);
  RapidClearance out;
  if (rapids.empty()) return out;
  const bool raised = uncertainty && uncertainty->size() == points.size();
  const double raise_max = raised ? *std::max_element(uncertainty->begin(), uncertainty->end()) : 0.0;
  const auto nearest_point = [&](const Eigen::Vector3d& c) {
    if (!raised) {
      std::uint32_t nearest;
      double d2;
      tree.knnSearch(c.data(), 1, &nearest, &d2);
      return std::sqrt(d2);
    }
    NearestRaised set{c, points, *uncertainty, raise_max};
    tree.findNeighbors(set, c.data(), nanoflann::SearchParams(32, 0, false));
    return std::sqrt(set.best2);
  };
  for (const CentreSegment& s : rapids) {
    if (!s.a.allFinite() || !s.b.allFinite()) throw std::invalid_argument("a rapid has a non-finite point");
    Eigen::Vector3d least_at = s.a;
    const double least = least_clearance_along(s.a, s.b, r, tol, nearest_point, &least_at);
    if (least < -tol) ++out.through;
    if (least < out.least) out.least = least, out.at = least_at;
  }
  return out;
}

// ----------------------------------------------------------------------------- simulation
SurfaceGridOptions surface_grid_options(const SimulateOptions& o) {
  SurfaceGridOptions g;
  g.tool_radius = o.tool_radius;
  g.scallop = o.scallop;
  g.spacing = o.spacing;
  g.max_samples = o.max_samples;
  g.loops = o.loops;
  g.rim_band = o.rim_band;
  return g;
}

namespace {
void check_simulation_inputs(const std::vector<CentreSegment>& feed, const SimulateOptions& o) {
  if (!(o.tool_radius > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(o.scallop > 0)) throw std::invalid_argument("scallop limit must be > 0");
  if (feed.empty()) throw std::invalid_argument("the path has no feed moves");
  for (const auto& s : feed)
    if (!s.a.allFinite() || !s.b.allFinite()) throw std::invalid_argument("the path has a non-finite point");
}
std::string describe(const SurfaceGridOptions& g) {
  std::size_t loop_points = 0;
  for (const auto& L : g.loops) loop_points += L.size();
  return "r " + short_number(g.tool_radius, 6) + ", h " + short_number(g.scallop, 6) + ", spacing " +
         short_number(g.spacing, 6) + ", max_samples " + std::to_string(g.max_samples) + ", rim_band " +
         short_number(g.rim_band, 6) + ", " + std::to_string(g.loops.size()) + " loops of " +
         std::to_string(loop_points) + " points";
}
}  // namespace

Simulation simulate_cut(const HeightFieldModel& surf, const std::vector<CentreSegment>& feed,
                        double rapid_length, const SimulateOptions& o,
                        const std::function<void(double)>& progress) {
  check_simulation_inputs(feed, o);
  const SurfaceSamples grid = sample_surface_grid(surf, surface_grid_options(o));
  return simulate_cut(surf, grid, feed, rapid_length, o, progress);
}

Simulation simulate_cut(const HeightFieldModel& surf, const SurfaceSamples& grid,
                        const std::vector<CentreSegment>& feed, double rapid_length, const SimulateOptions& o,
                        const std::function<void(double)>& progress) {
  check_simulation_inputs(feed, o);
  const double r = o.tool_radius, H = o.scallop;
  if (!(grid.options == surface_grid_options(o)))
    throw std::invalid_argument("the surface samples were taken for " + describe(grid.options) +
                                ", this simulation is for " + describe(surface_grid_options(o)) +
                                ": take them with the same tool radius, scallop limit, spacing, max_samples, rim_band "
                                "and loops");
  if (grid.cloud_points != surf.points().size())
    throw std::invalid_argument("the surface samples were taken from a cloud of " + std::to_string(grid.cloud_points) +
                                " points, this simulation's cloud has " + std::to_string(surf.points().size()));
  const bool use_loops = !o.loops.empty();
  const double stepover = std::sqrt(8 * r * H);
  const double margin = o.margin > 0 ? o.margin : stepover;
  const double gouge_tol = std::max(o.chord, 1e-3);
  const double T = 20 * H;
  const GridFrame g = grid_frame(grid);
  const double spacing = g.spacing;
  const int nu = g.nodes;
  const std::vector<std::uint8_t>& inside = grid.inside;

  // With loops the margin is measured from their edges, resampled every quarter spacing (the
  // nearest resampled point is at most an eighth of a spacing farther than the edge).
  std::vector<Eigen::Vector2d> edge_points;
  if (use_loops)
    for (const auto& L : o.loops)
      for (std::size_t k = 0; k < L.size(); ++k) {
        const Eigen::Vector2d a = L[k], b = L[(k + 1) % L.size()];
        const int m = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.25 * spacing))));
        for (int t = 0; t < m; ++t) edge_points.push_back(a + (b - a) * (double(t) / m));
      }
  const double rim_band = grid.rim_band;
  const Outline outline_polygons(use_loops ? o.loops : std::vector<std::vector<Eigen::Vector2d>>{});
  const std::size_t n_grid = grid.points.size();
  if (progress) progress(0.1);

  // Outline: grid nodes outside the patch next to one inside; interior = farther than the margin.
  std::vector<Eigen::Vector2d> outline;
  for (int j = 0; j < nu; ++j)
    for (int i = 0; i < nu; ++i) {
      if (inside[std::size_t(j) * nu + i]) continue;
      bool near = false;
      for (int dj = -1; dj <= 1 && !near; ++dj)
        for (int di = -1; di <= 1 && !near; ++di) {
          int ii = i + di, jj = j + dj;
          near = ii >= 0 && jj >= 0 && ii < nu && jj < nu && inside[std::size_t(jj) * nu + ii];
        }
      if (near) outline.push_back(g.xy(g.u(i), g.v(j)));
    }
  const std::vector<Eigen::Vector2d>& edge_set = use_loops ? edge_points : outline;
  PointsAdaptor<Eigen::Vector2d> outline_adaptor{edge_set};
  KdTree<Eigen::Vector2d, 2> outline_tree(2, outline_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  outline_tree.buildIndex();
  // The outline nodes lie up to a spacing outside the patch: measure from half a spacing in.
  const double edge_offset = use_loops ? 0.0 : 0.5 * spacing;
  // Whether (x, y) is farther than the margin from the outline. `last` carries what the previous
  // place of a row learnt: the distance to the outline changes no faster than the place moves,
  // so while a bound from the last search settles the answer no search is needed (most places
  // are far inside; the same answers).
  struct OutlineDistance {
    Eigen::Vector2d at{NAN, NAN};
    double lo = -INFINITY, hi = INFINITY;  // bounds on the distance at `at`
  };
  auto is_interior = [&](double x, double y, OutlineDistance& last) {
    if (edge_set.empty()) return true;
    const double threshold = margin + edge_offset, moved = (Eigen::Vector2d(x, y) - last.at).norm();
    constexpr double kSpare = 1e-9;  // for the rounding of the bounds
    if (std::isfinite(moved)) {
      last.at = {x, y}, last.lo -= moved, last.hi += moved;
      if (last.lo > threshold + kSpare) return true;
      if (last.hi < threshold - kSpare) return false;
    }
    std::uint32_t i;
    double d2;
    double q[2] = {x, y};
    outline_tree.knnSearch(q, 1, &i, &d2);
    last.at = {x, y}, last.lo = last.hi = std::sqrt(d2);
    return std::sqrt(d2) - edge_offset > margin;
  };
  // With loops, a refinement sample is on the patch when its nearest grid node is, and in the
  // rim band when that node is.
  auto nearest_node = [&](double x, double y) -> std::uint8_t {
    const std::ptrdiff_t at = g.nearest(x, y);
    return at >= 0 ? inside[std::size_t(at)] : 0;
  };
  auto on_patch_grid = [&](double x, double y) { return nearest_node(x, y) != 0; };
  auto in_band = [&](double x, double y) { return use_loops && nearest_node(x, y) == 2; };

  // Beside what was not machined: the ball touching the surface at p (normal n) would cut into it.
  const std::vector<Eigen::Vector3d> no_points;
  const std::vector<Eigen::Vector3d>& left_out = o.left_out ? *o.left_out : no_points;
  const PointsAdaptor<Eigen::Vector3d> left_out_adaptor{left_out};
  KdTree<Eigen::Vector3d, 3> left_out_tree(3, left_out_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  if (!left_out.empty()) left_out_tree.buildIndex();
  const double keep_off = obstacle_keep_off(r, surf.spacing());
  auto beside_left_out = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    if (left_out.empty()) return false;
    const Eigen::Vector3d c = p + r * n;
    std::uint32_t j;
    double d2;
    left_out_tree.knnSearch(c.data(), 1, &j, &d2);
    return d2 < keep_off * keep_off;
  };
  std::vector<std::uint8_t> unreachable(n_grid, 0);

  double cut_length = 0;
  for (const auto& s : feed) cut_length += (s.b - s.a).norm();
  CentreIndex index(feed, centre_piece_length(feed, spacing, r));

  Simulation res;
  res.spacing = spacing;
  res.scallop_limit = H;
  res.gouge_tolerance = gouge_tol;
  res.samples.resize(n_grid);
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
    std::vector<std::uint32_t> cand;
    for (int j = rg.begin(); j < rg.end(); ++j) {
      std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();  // the last sample's piece
      CentreIndex::CandidateCache pieces;
      pieces.slack = kCandidateSlack * spacing;
      OutlineDistance outline_distance;
      const std::size_t from = grid.row_start[j], to = grid.row_start[j + 1];
      for (std::size_t i = from; i < to; ++i) {
        const SurfacePoint& s = grid.points[i];
        SimSample& out = res.samples[i];
        out.x = s.p.x(), out.y = s.p.y(), out.z = s.p.z(), out.weight = s.weight;
        index.trace(s.p, s.n, r, T, s.uncertainty, out.gouge, out.scallop, cand, &hint, &pieces);
        out.interior = !s.beyond && is_interior(s.p.x(), s.p.y(), outline_distance);
        unreachable[i] = beside_left_out(s.p, s.n);
      }
      const std::size_t d = done.fetch_add(to - from) + to - from;
      if (progress) progress(0.1 + 0.7 * double(d) / n_grid);
    }
  });
  bool no_interior = std::none_of(res.samples.begin(), res.samples.end(), [](const SimSample& s) { return s.interior; });
  if (no_interior)
    for (auto& s : res.samples) s.interior = true;

  // Local refinement around the highest values (verify.py's levels: seeds, half-width/spacing).
  const std::pair<int, double> levels[] = {{1000, 1.0}, {100, 0.25}, {30, 1.0 / 16}};
  const auto grid_position = [&res](std::size_t i) -> Eigen::Vector3d {
    return {res.samples[i].x, res.samples[i].y, res.samples[i].z};
  };
  // Plain variables, not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
  for (const auto& level : levels) {
    const int K = level.first;
    const double halfw = level.second;
    std::vector<std::size_t> seeds;
    // A sample's value where it may seed, else NaN: the interior scallops, every reached one, the gouges.
    std::vector<double> value(res.samples.size());
    auto take = [&](auto of, std::size_t count) {
      for (std::size_t i = 0; i < res.samples.size(); ++i) value[i] = of(res.samples[i], i);
      const auto c = highest_values(value, count);
      seeds.insert(seeds.end(), c.begin(), c.end());
      if (&level == &levels[0]) {
        // ... and each cell's highest of the grid, lest a sharp lone peak be crowded out
        // (nodes/post/refinement_seeds.h)
        const auto cells = highest_per_cell_at(value, grid_position, kSeedCell * spacing, kSeedShare);
        seeds.insert(seeds.end(), cells.begin(), cells.end());
      }
    };
    take([&](const SimSample& s, std::size_t i) { return s.interior && !unreachable[i] ? s.scallop : kNaN; }, K);
    take([&](const SimSample& s, std::size_t i) { return !unreachable[i] ? s.scallop : kNaN; }, K / 4);
    take([](const SimSample& s, std::size_t) { return s.gouge; }, K / 4);
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    if (seeds.empty()) break;
    const int m = 4;  // (2m+1)² points per seed
    std::vector<SimSample> extra(seeds.size() * (2 * m + 1) * (2 * m + 1));
    std::vector<std::uint8_t> valid(extra.size(), 0), extra_unreachable(extra.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size()), [&](const tbb::blocked_range<std::size_t>& rg) {
      std::vector<std::uint32_t> cand;
      for (std::size_t si = rg.begin(); si < rg.end(); ++si) {
        const SimSample c = res.samples[seeds[si]];
        std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();
        CentreIndex::CandidateCache pieces;
        pieces.slack = kCandidateSlack * halfw * spacing;
        OutlineDistance outline_distance;
        for (int a = -m; a <= m; ++a)
          for (int b = -m; b <= m; ++b) {
            double du = halfw * spacing * a / m, dv = halfw * spacing * b / m;
            double x = c.x + g.ca * du - g.sa * dv, y = c.y + g.sa * du + g.ca * dv, z, u;
            Eigen::Vector3d n;
            std::size_t slot = (si * (2 * m + 1) + (a + m)) * (2 * m + 1) + (b + m);
            if (use_loops ? !(on_patch_grid(x, y) && surf.eval(x, y, z, n, true, &u))
                          : !surf.eval(x, y, z, n, false, &u))
              continue;
            // no farther out than the grid's samples: inside the loops, or in the rim band up to
            // its edge (the nearest node's rule alone let one half a spacing over the loop)
            if (use_loops && outline_polygons.beyond({x, y}) > rim_band * n.z()) continue;
            SimSample& out = extra[slot];
            out.x = x, out.y = y, out.z = z, out.weight = 0;
            index.trace({x, y, z}, n, r, T, u, out.gouge, out.scallop, cand, &hint, &pieces);
            out.interior = no_interior || (!in_band(x, y) && is_interior(x, y, outline_distance));
            extra_unreachable[slot] = beside_left_out({x, y, z}, n);
            valid[slot] = 1;
          }
      }
    });
    for (std::size_t i = 0; i < extra.size(); ++i)
      if (valid[i]) res.samples.push_back(extra[i]), unreachable.push_back(extra_unreachable[i]);
  }
  if (progress) progress(0.95);

  // Statistics: area-weighted over the grid; maxima include the refinement samples.
  auto& rep = res.report;
  double area = 0, area_i = 0, uncut = 0, uncut_i = 0, gouge_max = 0;
  std::vector<std::pair<double, double>> all, inner;
  double max_all = -INFINITY, max_inner = -INFINITY;
  std::size_t n_interior = 0, n_beyond = 0, gouge_at = 0, scallop_at = 0;
  double beside_area = 0;
  Eigen::Vector2d beside_min = Eigen::Vector2d::Constant(INFINITY), beside_max = -beside_min;
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    if (s.gouge > gouge_max) gouge_max = s.gouge, gouge_at = i;
    if (unreachable[i]) {
      if (i < n_grid) beside_area += s.weight;
      beside_min = beside_min.cwiseMin(Eigen::Vector2d(s.x, s.y));
      beside_max = beside_max.cwiseMax(Eigen::Vector2d(s.x, s.y));
      continue;
    }
    bool cut = !std::isnan(s.scallop);
    if (cut) {
      if (s.scallop > max_all) scallop_at = i;
      max_all = std::max(max_all, s.scallop);
      if (s.interior) max_inner = std::max(max_inner, s.scallop);
    }
    if (i >= n_grid) continue;
    area += s.weight;
    if (s.interior) area_i += s.weight, ++n_interior;
    if (nearest_node(s.x, s.y) == 2) ++n_beyond;
    if (!cut) {
      uncut += s.weight;
      if (s.interior) uncut_i += s.weight;
      continue;
    }
    all.emplace_back(s.scallop, s.weight);
    if (s.interior) inner.emplace_back(s.scallop, s.weight);
  }
  if (!std::isfinite(max_all)) max_all = kNaN;
  if (!std::isfinite(max_inner)) max_inner = kNaN;
  WeightedStats st = weighted_stats(std::move(all)), sti = weighted_stats(std::move(inner));
  rep["tool_radius"] = r;
  rep["scallop_limit"] = H;
  rep["chord_limit"] = o.chord;
  rep["spacing"] = spacing;
  rep["margin"] = margin;
  rep["rim_band"] = rim_band;
  rep["samples"] = n_grid;
  rep["samples_interior"] = n_interior;
  rep["samples_beyond_outline"] = n_beyond;
  rep["samples_refined"] = res.samples.size() - n_grid;
  rep["surface_area"] = area;
  if (o.left_out) {
    const double whole = area + beside_area;
    rep["beside_left_out"] = {{"area_mm2", beside_area},
                              {"fraction", whole > 0 ? beside_area / whole : 0.0},
                              {"min", beside_area > 0 ? nlohmann::json({beside_min.x(), beside_min.y()}) : nlohmann::json()},
                              {"max", beside_area > 0 ? nlohmann::json({beside_max.x(), beside_max.y()}) : nlohmann::json()}};
  }
  report_scallop(rep, max_all, max_inner, st, sti);
  rep["gouge_max"] = gouge_max;
  rep["uncut_fraction"] = area > 0 ? uncut / area : 0.0;
  rep["uncut_fraction_interior"] = area_i > 0 ? uncut_i / area_i : 0.0;
  rep["cut_length"] = cut_length;
  rep["rapid_length"] = rapid_length;
  // how far the cloud may be off the real surface: scallop and gouge above include it
  rep["surface_uncertainty_max"] = surf.uncertainty_max();
  // and the largest the bounds used at a grid sample: the model's, its fit's misfit counted
  rep["surface_uncertainty_max_sampled"] = grid.uncertainty_max;

  nlohmann::json reasons = nlohmann::json::array();
  char buf[160];
  // Where a bound is over its limit, how much of it the cloud's surface itself shows and how much
  // is the surface's uncertainty there (both bounds are the value on the surface plus it): a
  // bound that is mostly uncertainty asks for a better scan, not another program.
  // A gouge bound below the uncertainty is a ball that clears the cloud's surface by less than
  // the surface is known (on a noisy dome, "0 on the cloud's surface" read as a touch where the
  // ball stayed 0.013 mm off).
  auto split = [&](const SimSample& at, double bound) {
    const double u = surf.uncertainty(at.x, at.y), on_surface = bound - u;
    char part[240];
    if (on_surface < 0)
      std::snprintf(part, sizeof part,
                    ": at (%.4g, %.4g) the ball stays %.4g clear of the cloud's surface, less than its "
                    "uncertainty there, %.4g (a finer scan there would tighten it)",
                    at.x, at.y, -on_surface, u);
    else
      std::snprintf(part, sizeof part, ": at (%.4g, %.4g) %.4g on the cloud's surface and %.4g its uncertainty there%s",
                    at.x, at.y, on_surface, u,
                    u > 0.5 * bound ? " (mostly uncertainty: a finer scan there would tighten it)" : "");
    return std::string(part);
  };
  // The whole patch counts, rim included: the rim is part of the part.
  if (std::isnan(max_all)) {
    reasons.push_back("no sample was cut");
  } else if (max_all > 1.01 * H) {
    std::snprintf(buf, sizeof buf, "scallop max %.4g > 1.01 H (rim included; interior %.4g)",
                  max_all, max_inner);
    reasons.push_back(buf + split(res.samples[scallop_at], max_all));
  }
  if (gouge_max > gouge_tol) {
    std::snprintf(buf, sizeof buf, "gouge max %.4g > %.4g", gouge_max, gouge_tol);
    reasons.push_back(buf + split(res.samples[gouge_at], gouge_max));
  }
  if (uncut > 0) {
    std::snprintf(buf, sizeof buf, "uncut fraction %.4g > 0", uncut / area);
    reasons.push_back(buf);
  }
  rep["pass"] = reasons.empty();
  rep["fail_reasons"] = reasons;

  // The ten worst places, at least a stepover apart: gouges beyond tolerance, then uncut spots,
  // then scallops, each ranked by how far it is over its limit.
  std::vector<std::pair<double, std::size_t>> rank;
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    double score = unreachable[i] ? 0.0 : std::isnan(s.scallop) ? 1e6 : s.scallop / H;
    if (s.gouge > gouge_tol) score = 1e9 + s.gouge / gouge_tol;
    if (score > 0) rank.emplace_back(score, i);
  }
  // Taken from a max-heap in the order a full sort would give (no two entries are equal), and
  // only as far as the ten places reach.
  std::make_heap(rank.begin(), rank.end());
  nlohmann::json worst = nlohmann::json::array();
  std::vector<Eigen::Vector2d> taken;
  while (!rank.empty() && worst.size() < 10) {
    std::pop_heap(rank.begin(), rank.end());
    const std::size_t i = rank.back().second;
    rank.pop_back();
    const SimSample& s = res.samples[i];
    Eigen::Vector2d q(s.x, s.y);
    if (std::any_of(taken.begin(), taken.end(), [&](const auto& t) { return (t - q).norm() < stepover; })) continue;
    taken.push_back(q);
    std::string kind = s.gouge > gouge_tol ? "gouge" : std::isnan(s.scallop) ? "uncut" : "scallop";
    nlohmann::json v = kind == "gouge" ? nlohmann::json(s.gouge) : kind == "uncut" ? nlohmann::json() : nlohmann::json(s.scallop);
    worst.push_back({{"x", s.x}, {"y", s.y}, {"z", s.z}, {"kind", kind}, {"value", v}, {"interior", s.interior},
                     {"uncertainty", surf.uncertainty(s.x, s.y)}});
  }
  rep["worst"] = worst;
  res.outline = std::move(outline);
  if (progress) progress(1.0);
  return res;
}

}  // namespace scallop
