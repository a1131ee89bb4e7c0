#include "nodes/post/simulate_part.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <memory>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/self_crossings.h"
#include "nodes/post/clearance_march.h"
#include "nodes/post/part_samples.h"
#include "nodes/post/refinement_seeds.h"

namespace scallop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// Border edges and edges whose two faces' normals differ by more than `angle`, as segments.
std::vector<CentreSegment> edges_to_keep_off(const Mesh& m, const std::vector<PartTriangle>& tris, double angle) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<Eigen::Vector3d>> normals;
  std::vector<Eigen::Vector3d> face_normal(m.num_faces(), Eigen::Vector3d::Zero());
  for (const PartTriangle& t : tris) face_normal[t.face] += t.n;
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const std::size_t k = m.face_size(f);
    for (std::size_t i = 0; i < k; ++i) {
      std::uint32_t a = m.face(f)[i], b = m.face(f)[(i + 1) % k];
      normals[{std::min(a, b), std::max(a, b)}].push_back(face_normal[f].normalized());
    }
  }
  const double cos_angle = std::cos(angle * kPi / 180);
  std::vector<CentreSegment> out;
  for (const auto& [e, ns] : normals) {
    bool keep = ns.size() != 2;
    if (!keep) keep = !(ns[0].dot(ns[1]) >= cos_angle);
    if (keep) out.push_back({m.vertices[e.first], m.vertices[e.second]});
  }
  return out;
}

nlohmann::json xyz(const Eigen::Vector3d& p) { return {{"x", p.x()}, {"y", p.y()}, {"z", p.z()}}; }

// The least clearance D(c) - r along a rapid's ball centres [a, b], marched by the clearance
// itself (it cannot fall faster than c moves), to within `tol` / 2.
double rapid_clearance(const MeshDistance& part, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                       double tol) {
  return least_clearance_along(a, b, r, tol, [&](const Eigen::Vector3d& c) { return part.signed_distance(c); });
}

}  // namespace

Simulation simulate_part(const Mesh& part, const std::vector<PartSetupCut>& setups, const PartSimulateOptions& o,
                         const std::function<void(double)>& progress, const Mesh* outer, const Mesh* inner_mesh,
                         const std::vector<Eigen::Vector3d>* cloud) {
  const double r = o.tool_radius, H = o.scallop, delta = o.surface_uncertainty;
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(H > 0)) throw std::invalid_argument("scallop limit must be > 0");
  if (!(H < r)) {
    char text[160];
    std::snprintf(text, sizeof text, "the scallop limit %g mm is not below the tool radius %g mm", H, r);
    throw std::invalid_argument(text);
  }
  if (!(delta >= 0) || !std::isfinite(delta)) throw std::invalid_argument("surface uncertainty must be >= 0");
  if (setups.empty()) throw std::invalid_argument("no setup to simulate");
  std::vector<CentreSegment> feed;
  std::vector<std::uint32_t> feed_setup;
  for (std::size_t s = 0; s < setups.size(); ++s) {
    for (const auto* list : {&setups[s].feed, &setups[s].rapid})
      for (const CentreSegment& c : *list)
        if (!c.a.allFinite() || !c.b.allFinite())
          throw std::invalid_argument("setup '" + setups[s].name + "' has a ball centre that is not finite");
    feed.insert(feed.end(), setups[s].feed.begin(), setups[s].feed.end());
    feed_setup.insert(feed_setup.end(), setups[s].feed.size(), std::uint32_t(s));
  }
  if (feed.empty()) throw std::invalid_argument("no setup has a feed move");
  const std::vector<PartTriangle> tris = part_triangles(part);
  if (tris.empty()) throw std::invalid_argument("the part's mesh has no face with an area");
  const double tol = std::max(o.chord, 1e-3);
  const double nominal = std::sqrt(8 * r * H);
  const double edge_uncertainty = o.edge_uncertainty_edges > 0
                                      ? std::max(o.edge_uncertainty, o.edge_uncertainty_edges * mean_edge_length(part))
                                      : o.edge_uncertainty;
  const double margin = std::max(0.0, (o.margin > 0 ? o.margin : nominal) - edge_uncertainty);
  const double T = 20 * H;

  // Spacing: raised until the samples fit max_samples.
  const double spacing = o.spacing > 0 ? o.spacing : part_sample_spacing(tris, nominal / 8, o.max_samples);
  std::vector<PartSample> samples = sample_part(tris, spacing);
  if (progress) progress(0.05);

  // Where the part's mesh crosses itself, its tangled faces do not tell the side by their normals
  // (nor the outer mesh's, the same faces moved): the rays do.
  const SelfCrossings crossings = self_crossings(part);
  const MeshDistance distance(part, nullptr, crossings.tangled);
  if (outer && outer->num_faces() == 0) throw std::invalid_argument("the outer mesh has no face");
  if (inner_mesh && !inner_mesh->same_faces(part))
    throw std::invalid_argument("the inner mesh is not the part's mesh with its vertices moved (its faces differ)");
  // The outer mesh is the part's moved outward: a face the moves turned over does not tell the side.
  const bool outer_moved = outer && outer->same_faces(part);
  const std::unique_ptr<const MeshDistance> outer_distance =
      outer ? std::make_unique<const MeshDistance>(*outer, outer_moved ? &part : nullptr,
                                                   outer_moved ? std::span<const std::size_t>(crossings.tangled)
                                                               : std::span<const std::size_t>())
            : nullptr;
  const MeshDistance& gouge_distance = outer ? *outer_distance : distance;  // what balls must stay off
  const CentreIndex keep_off(edges_to_keep_off(part, tris, o.feature_angle), std::max(spacing, margin / 2));
  const CentreIndex centres(feed, centre_piece_length(feed, spacing, r));

  // Classify and trace every sample: 0 measured, 1 base, 2 unreachable.
  const bool has_base = o.base_normal.norm() > 0;
  const Eigen::Vector3d base_n = has_base ? Eigen::Vector3d(o.base_normal.normalized()) : Eigen::Vector3d::Zero();
  const double cos_base = std::cos(o.base_angle * kPi / 180);
  auto reaches = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius) {
    return ball_reaches(distance, p, n, radius, tol);
  };
  struct Traced {
    int kind = 0;
    double scallop = kNaN, gouge = 0, reach = 0;
    double clearance = 0;  // ball_clearance of the tangent ball of radius r
    bool interior = false;
    std::uint32_t finisher = 0;
  };
  std::vector<Traced> traced(samples.size());
  std::atomic<std::size_t> done{0};
  // measure_reach: find the largest radius that reaches an unreachable sample (the report's
  // unreachable places and the refinement's seeds read it from the grid's samples only).
  auto trace_one = [&](const PartSample& s, Traced& out, std::vector<std::uint32_t>& cand, bool measure_reach) {
    const Eigen::Vector3d& n = tris[s.tri].n;
    if (has_base && n.dot(base_n) >= cos_base) {
      out.kind = 1;
      return;
    }
    out.clearance = ball_clearance(distance, s.p, n, r, tol);
    if (!(out.clearance >= 0)) {
      out.kind = 2;
      if (!measure_reach) return;
      // The largest radius that reaches, by bisection, to r / 32768 below (6e-5 mm at r = 2): 30
      // halvings were a third of the fandisk cloud's certificate, 68 s -> 47 s.
      double lo = 0, hi = r;
      for (int it = 0; it < 15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (reaches(s.p, n, mid) ? lo : hi) = mid;
      }
      out.reach = lo;
      return;
    }
    const Eigen::Vector3d from = inner_mesh ? same_place(tris[s.tri], s.p, inner_mesh->vertices) : s.p;
    // The setup that finished it: the one whose piece the ray entered first (or that holds p):
    // trace names it (asking for the piece nearest the entry point, as before, searched every
    // piece within r of it, a quarter of the certificate's time on the block's cloud).
    std::uint32_t piece_at = std::numeric_limits<std::uint32_t>::max();
    centres.trace(from, n, r, T, delta, out.gouge, out.scallop, cand, &piece_at);
    out.interior = !std::isfinite(keep_off.distance(s.p, margin, cand));
    if (!std::isnan(out.scallop) && piece_at != std::numeric_limits<std::uint32_t>::max())
      out.finisher = feed_setup[centres.segment_of(piece_at)];
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 512), [&](const tbb::blocked_range<std::size_t>& rg) {
    std::vector<std::uint32_t> cand;
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) trace_one(samples[i], traced[i], cand, true);
    const std::size_t d = done.fetch_add(rg.size()) + rg.size();
    if (progress) progress(0.05 + 0.6 * double(d) / samples.size());
  });
  const std::size_t n_grid = samples.size();
  bool no_interior = true;
  for (const Traced& t : traced) no_interior = no_interior && !(t.kind == 0 && t.interior);
  if (no_interior)
    for (Traced& t : traced) t.interior = true;

  // Local refinement around the highest scallops, inside their own triangles (verify_part.py's
  // levels: seeds, half-width / spacing; a cusp's slope makes the maximum's error linear in the
  // finest step, spacing / 1024). The first level seeds from the highest 1 % where that is more
  // than the judge's 1000: after rest passes many crests stand near the top, and on the ABC plate
  // the judge's highest 1000 held one the certificate's did not (0.0178 against 0.0166).
  const int first_seeds = static_cast<int>(std::max<std::size_t>(1000, n_grid / 100));
  const std::pair<int, double> levels[] = {{first_seeds, 1.0}, {100, 0.25}, {30, 1.0 / 16}, {10, 1.0 / 64}, {10, 1.0 / 256}};
  const auto grid_position = [&samples](std::size_t i) { return samples[i].p; };
  for (const auto& level : levels) {
    std::vector<std::size_t> seeds;
    std::vector<double> value(samples.size());
    for (bool interior_only : {true, false}) {
      for (std::size_t i = 0; i < samples.size(); ++i)
        value[i] = traced[i].kind == 0 && (!interior_only || traced[i].interior) ? traced[i].scallop : kNaN;
      const auto c = highest_values(value, interior_only ? level.first : level.first / 4);
      seeds.insert(seeds.end(), c.begin(), c.end());
      if (&level == &levels[0]) {
        // ... and each cell's highest, lest a sharp lone peak be crowded out (refinement_seeds.h)
        const auto cells = highest_per_cell_at(value, grid_position, kSeedCell * spacing, kSeedShare);
        seeds.insert(seeds.end(), cells.begin(), cells.end());
      }
    }
    if (&level == &levels[0])
      // ... and the samples a ball of nearly radius r reaches: beside a concave edge the band a
      // ball reaches is thin, the material left there high, and a grid may have no measured
      // sample in it (the block kept 0.044 mm there that only the judge's samples found).
      for (std::size_t i = 0; i < n_grid; ++i)
        if (traced[i].kind == 2 && traced[i].reach >= 0.9 * r) seeds.push_back(i);
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    if (seeds.empty()) break;
    // (2m+1)² points per seed, m = 4; 8 where the edge of the ball's reach may cross the seed's
    // square (an out-of-reach seed, or one whose clearance is less than the square's half
    // diagonal: the clearance changes no faster than the sample moves). The part of the square a
    // ball reaches can be a sliver a few hundredths of a millimetre wide there, with the most
    // material left in it: on the fandisk after rest passes, 0.0194 mm that m = 4 missed (it
    // found 0.0181 elsewhere), where the judge found 0.0194.
    const double half_diagonal = std::sqrt(2.0) * level.second * spacing;
    auto m_of = [&](std::size_t seed) {
      return traced[seed].kind == 2 || traced[seed].clearance < half_diagonal ? 8 : 4;
    };
    std::vector<std::size_t> first_slot(seeds.size() + 1, 0);
    for (std::size_t si = 0; si < seeds.size(); ++si)
      first_slot[si + 1] = first_slot[si] + std::size_t((2 * m_of(seeds[si]) + 1) * (2 * m_of(seeds[si]) + 1));
    std::vector<PartSample> extra(first_slot.back());
    std::vector<Traced> extra_traced(extra.size());
    std::vector<std::uint8_t> valid(extra.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size()), [&](const tbb::blocked_range<std::size_t>& rg) {
      std::vector<std::uint32_t> cand;
      for (std::size_t si = rg.begin(); si < rg.end(); ++si) {
        const PartSample seed = samples[seeds[si]];
        const PartTriangle& t = tris[seed.tri];
        const Eigen::Vector3d e1 = (t.b - t.a).normalized(), e2 = t.n.cross(e1);
        const int m = m_of(seeds[si]);
        for (int a = -m; a <= m; ++a)
          for (int b = -m; b <= m; ++b) {
            const std::size_t slot = first_slot[si] + std::size_t((a + m) * (2 * m + 1) + (b + m));
            const Eigen::Vector3d p = seed.p + level.second * spacing * (a * e1 + b * e2) / m;
            if (!in_part_triangle(t, p)) continue;
            extra[slot] = {p, 0, seed.tri};
            // (their reach unmeasured: 535 000 such points, 15 tests each, were two thirds of
            // the fandisk cloud's certificate)
            trace_one(extra[slot], extra_traced[slot], cand, false);
            if (no_interior) extra_traced[slot].interior = true;
            valid[slot] = 1;
          }
      }
    });
    for (std::size_t i = 0; i < extra.size(); ++i)
      if (valid[i]) samples.push_back(extra[i]), traced.push_back(extra_traced[i]);
  }
  if (progress) progress(0.7);

  // Gouge and rapids, setup by setup.
  nlohmann::json per_setup = nlohmann::json::array();
  double gouge_max = 0, rapid_min = INFINITY, cut_total = 0, rapid_total = 0;
  std::size_t through_total = 0;
  double measured_area = 0;
  std::vector<double> finished(setups.size(), 0);
  for (std::size_t i = 0; i < n_grid; ++i)
    if (traced[i].kind == 0) {
      measured_area += samples[i].weight;
      if (!std::isnan(traced[i].scallop)) finished[traced[i].finisher] += samples[i].weight;
    }
  struct MoveGouge {
    double depth;
    Eigen::Vector3d centre;  // the ball centre where a move reaches deepest into the part
    std::string setup;
  };
  std::vector<MoveGouge> move_gouges;  // each setup's deepest, where over the tolerance
  for (std::size_t s = 0; s < setups.size(); ++s) {
    const PartSetupCut& cut = setups[s];
    using Deepest = std::pair<double, Eigen::Vector3d>;  // a gouge bound and where (ball centre)
    tbb::combinable<Deepest> g_max([] { return Deepest{-INFINITY, Eigen::Vector3d::Zero()}; });
    tbb::combinable<double> r_min([] { return INFINITY; });
    tbb::combinable<std::size_t> through([] { return std::size_t(0); }), positions([] { return std::size_t(0); });
    tbb::parallel_for(std::size_t(0), cut.feed.size(), [&](std::size_t k) {
      Eigen::Vector3d at;
      // r + delta - D: an upper bound within 1e-5 of the truth where it exceeds tol.
      const double g = r + delta - gouge_distance.least_along(cut.feed[k].a, cut.feed[k].b, spacing, r + delta - tol, 1e-5,
                                                        at, positions.local());
      if (g > g_max.local().first) g_max.local() = {g, at};
    });
    tbb::parallel_for(std::size_t(0), cut.rapid.size(), [&](std::size_t k) {
      const double c = rapid_clearance(gouge_distance, cut.rapid[k].a, cut.rapid[k].b, r, tol);
      r_min.local() = std::min(r_min.local(), c);
      if (c < -tol) ++through.local();
    });
    const Deepest deepest = g_max.combine([](const Deepest& a, const Deepest& b) { return a.first >= b.first ? a : b; });
    const double g = std::max(0.0, deepest.first);
    const double rc = r_min.combine([](double a, double b) { return std::min(a, b); });
    const std::size_t thr = through.combine(std::plus<>());
    double cut_length = 0, rapid_length = 0;
    for (const auto& c : cut.feed) cut_length += (c.b - c.a).norm();
    for (const auto& c : cut.rapid) rapid_length += (c.b - c.a).norm();
    gouge_max = std::max(gouge_max, g);
    if (g > tol) move_gouges.push_back({g, deepest.second, cut.name});
    rapid_min = std::min(rapid_min, rc);
    through_total += thr;
    cut_total += cut_length, rapid_total += rapid_length;
    per_setup.push_back({{"name", cut.name},
                         {"cut_length", cut_length},
                         {"rapid_length", rapid_length},
                         {"gouge_max", g},
                         {"gouge_at", g > 0 ? xyz(deepest.second) : nlohmann::json()},
                         {"ball_positions", positions.combine(std::plus<>())},
                         {"rapid_min_clearance", finite_or_null(rc)},
                         {"rapids_through_part", thr},
                         {"finished_fraction", measured_area > 0 ? finished[s] / measured_area : 0.0}});
    if (progress) progress(0.7 + 0.28 * double(s + 1) / setups.size());
  }

  // The cloud's own points, in one pass:
  //  - inside a ball: the part cut away, whatever the meshes say;
  //  - outside the outer mesh by x: the gouge is measured against that mesh, a bound on the part
  //    only where it holds the cloud; such a point shows the part standing out of it, and between
  //    the points more may (an edge the mesh bevels). A ball passing within r + x of it may cut
  //    what the outer mesh does not show, so there the gouge is not bounded.
  using Deepest = std::pair<double, Eigen::Vector3d>;  // a depth and where
  const auto deeper = [](const Deepest& a, const Deepest& b) { return a.first >= b.first ? a : b; };
  struct CloudTally {
    Deepest cut_deepest{0.0, Eigen::Vector3d::Zero()}, unbounded_farthest{0.0, Eigen::Vector3d::Zero()};
    std::size_t cut = 0, unbounded = 0;
  };
  CloudTally cloud_tally;
  if (cloud) {
    tbb::combinable<CloudTally> tally;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud->size(), 4096), [&](const tbb::blocked_range<std::size_t>& b) {
      std::vector<std::uint32_t> scratch;
      CloudTally& t = tally.local();
      for (std::size_t i = b.begin(); i < b.end(); ++i) {
        const Eigen::Vector3d& p = (*cloud)[i];
        const double d = centres.distance(p, r, scratch);
        if (std::isfinite(d)) {
          if (r - d > tol) ++t.cut;
          t.cut_deepest = deeper(t.cut_deepest, {r - d, p});
        }
        if (!outer) continue;
        const double x = gouge_distance.signed_distance(p);
        if (!(x > tol) || !(centres.distance(p, r + x, scratch) < r + x)) continue;
        ++t.unbounded;
        t.unbounded_farthest = deeper(t.unbounded_farthest, {x, p});
      }
    });
    tally.combine_each([&](const CloudTally& t) {
      cloud_tally.cut += t.cut, cloud_tally.unbounded += t.unbounded;
      cloud_tally.cut_deepest = deeper(cloud_tally.cut_deepest, t.cut_deepest);
      cloud_tally.unbounded_farthest = deeper(cloud_tally.unbounded_farthest, t.unbounded_farthest);
    });
    gouge_max = std::max(gouge_max, cloud_tally.cut_deepest.first);
  }
  const Deepest& cloud_deepest = cloud_tally.cut_deepest;
  const Deepest& unbounded = cloud_tally.unbounded_farthest;
  const std::size_t cloud_cut = cloud_tally.cut, unbounded_points = cloud_tally.unbounded;

  // Where the part's mesh crosses itself (a reconstruction tangled at a gap finer than its
  // points), the faces there bound nothing; the part is taken to lie within half the margin of
  // them (tangle_keep_out). A ball centre nearer than r + 3/4 of the margin to a sample may come
  // within half of it of a face: the gouge there is not bounded (post.setup_programs keeps the
  // balls r + margin off the samples). Not the outer mesh's: moved out, it crosses itself at every
  // concave edge, and its union still bounds the part.
  const TangleKeepOut keep = tangle_keep_out(part, crossings, o.tangle_margin);
  std::size_t tangle_samples_reached = 0;
  Deepest tangle_nearest{-INFINITY, Eigen::Vector3d::Zero()};  // minus the distance, and where
  {
    const double reach = r + 0.75 * keep.margin;
    std::vector<std::uint32_t> scratch;
    for (const Eigen::Vector3d& q : keep.samples) {
      const double d = centres.distance(q, reach, scratch);
      if (!(d < reach)) continue;
      ++tangle_samples_reached;
      tangle_nearest = deeper(tangle_nearest, {-d, q});
    }
  }

  // Statistics: area-weighted over the grid; maxima include the refinement samples.
  Simulation res;
  res.spacing = spacing;
  res.scallop_limit = H;
  res.gouge_tolerance = tol;
  double area = 0, base_area = 0, unreachable_area = 0, area_i = 0, uncut = 0, uncut_i = 0, over = 0, over_i = 0;
  double max_all = -INFINITY, max_inner = -INFINITY;
  std::vector<std::pair<double, double>> all, inner;
  std::size_t n_measured = 0, n_interior = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const PartSample& s = samples[i];
    const Traced& t = traced[i];
    const bool grid = i < n_grid;
    if (grid) {
      area += s.weight;
      if (t.kind == 1) base_area += s.weight;
      if (t.kind == 2) unreachable_area += s.weight;
    }
    if (t.kind != 0) continue;
    res.samples.push_back({s.p.x(), s.p.y(), s.p.z(), s.weight, t.scallop, t.gouge, t.interior});
    res.face.push_back(tris[s.tri].face);
    const bool cut = !std::isnan(t.scallop);
    const bool bad = !cut || t.scallop > 1.01 * H;
    if (cut) {
      max_all = std::max(max_all, t.scallop);
      if (t.interior) max_inner = std::max(max_inner, t.scallop);
    }
    if (!grid) continue;
    ++n_measured;
    if (t.interior) ++n_interior, area_i += s.weight;
    if (cut) {
      all.emplace_back(t.scallop, s.weight);
      if (t.interior) inner.emplace_back(t.scallop, s.weight);
    } else {
      uncut += s.weight;
      if (t.interior) uncut_i += s.weight;
    }
    if (bad) {
      over += s.weight;
      if (t.interior) over_i += s.weight;
    }
  }
  const double measured = area - base_area - unreachable_area;
  const WeightedStats st = weighted_stats(std::move(all)), sti = weighted_stats(std::move(inner));
  auto& rep = res.report;
  report_scallop(rep, max_all, max_inner, st, sti);
  rep["frac_over_limit"] = measured > 0 ? nlohmann::json(over / measured) : nlohmann::json();
  rep["frac_over_limit_interior"] = area_i > 0 ? nlohmann::json(over_i / area_i) : nlohmann::json();
  rep["uncut_fraction"] = measured > 0 ? nlohmann::json(uncut / measured) : nlohmann::json();
  rep["uncut_fraction_interior"] = area_i > 0 ? nlohmann::json(uncut_i / area_i) : nlohmann::json();
  rep["gouge_max"] = gouge_max;
  if (cloud) {
    rep["gouge_max_cloud"] = cloud_deepest.first;
    rep["gouge_cloud_at"] = cloud_deepest.first > 0 ? xyz(cloud_deepest.second) : nlohmann::json();
    rep["cloud_points_cut"] = cloud_cut;
  }
  if (cloud && outer) {
    rep["gouge_unbounded_points"] = unbounded_points;
    rep["gouge_unbounded_max"] = unbounded.first;
    rep["gouge_unbounded_at"] = unbounded_points > 0 ? xyz(unbounded.second) : nlohmann::json();
  }
  rep["crossing_pairs"] = crossings.pairs.size();
  rep["tangled_faces"] = crossings.tangled.size();
  rep["tangle_margin"] = keep.margin;
  rep["tangle_samples_reached"] = tangle_samples_reached;
  rep["tangle_reached_at"] = tangle_samples_reached > 0 ? xyz(tangle_nearest.second) : nlohmann::json();
  rep["rapids_through_part"] = through_total;
  rep["rapid_min_clearance"] = finite_or_null(rapid_min);
  rep["cut_length"] = cut_total;
  rep["rapid_length"] = rapid_total;
  rep["surface_area"] = area;
  rep["base_fraction"] = base_area / area;
  rep["unreachable_fraction"] = unreachable_area / area;
  rep["measured_fraction"] = measured / area;
  rep["samples"] = n_grid;
  rep["samples_measured"] = n_measured;
  rep["samples_interior"] = n_interior;
  rep["samples_refined"] = samples.size() - n_grid;
  rep["spacing"] = spacing;
  rep["margin"] = margin;
  rep["edge_uncertainty"] = edge_uncertainty;
  rep["surface_uncertainty"] = delta;
  rep["tool_radius"] = r;
  rep["scallop_limit"] = H;
  rep["chord_limit"] = o.chord;
  rep["setups"] = per_setup;

  // Unreachable places, 2 r apart, the smallest reach first.
  std::vector<std::size_t> unreachable;
  for (std::size_t i = 0; i < n_grid; ++i)
    if (traced[i].kind == 2) unreachable.push_back(i);
  std::sort(unreachable.begin(), unreachable.end(), [&](auto a, auto b) { return traced[a].reach < traced[b].reach; });
  nlohmann::json places = nlohmann::json::array();
  std::vector<Eigen::Vector3d> chosen;
  for (std::size_t i : unreachable) {
    if (chosen.size() == 10) break;
    const Eigen::Vector3d& p = samples[i].p;
    if (std::any_of(chosen.begin(), chosen.end(), [&](const auto& c) { return (c - p).norm() < 2 * r; })) continue;
    chosen.push_back(p);
    nlohmann::json place = xyz(p);
    place["reach_radius"] = traced[i].reach;
    places.push_back(place);
  }
  rep["unreachable"] = places;

  // The worst places, one per stepover around: first the moves that reach into the part beyond
  // the tolerance (each setup's deepest, at its ball centre: a move can gouge where no surface
  // sample shows it, through a thin wall), then uncut, gouges and scallops over the limit at the
  // surface samples, interior ones (what pass asks) before the others, each by its excess.
  enum Kind { Scallop, Gouge, Uncut };
  std::vector<std::tuple<bool, double, std::size_t, Kind>> rank;
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    if (std::isnan(s.scallop)) rank.emplace_back(s.interior, 1e9, i, Uncut);
    else if (s.scallop > 1.01 * H) rank.emplace_back(s.interior, s.scallop / H, i, Scallop);
    if (s.gouge > tol) rank.emplace_back(true, 1e6 * s.gouge / tol, i, Gouge);
  }
  std::sort(rank.rbegin(), rank.rend());
  nlohmann::json worst = nlohmann::json::array();
  std::vector<Eigen::Vector3d> listed;
  std::sort(move_gouges.begin(), move_gouges.end(), [](const MoveGouge& a, const MoveGouge& b) { return a.depth > b.depth; });
  for (const MoveGouge& m : move_gouges) {
    if (worst.size() == 10) break;
    listed.push_back(m.centre);
    nlohmann::json w = xyz(m.centre);
    w["kind"] = "gouge";
    w["value"] = m.depth;
    w["at"] = "ball centre";
    w["setup"] = m.setup;
    worst.push_back(w);
  }
  for (const auto& [interior, score, i, kind] : rank) {
    if (worst.size() == 10) break;
    const SimSample& s = res.samples[i];
    const Eigen::Vector3d p(s.x, s.y, s.z);
    if (std::any_of(listed.begin(), listed.end(), [&](const auto& q) { return (q - p).norm() < nominal; })) continue;
    listed.push_back(p);
    nlohmann::json w = xyz(p);
    w["kind"] = kind == Uncut ? "uncut" : kind == Gouge ? "gouge" : "scallop";
    w["value"] = kind == Uncut ? nlohmann::json() : nlohmann::json(kind == Gouge ? s.gouge : s.scallop);
    w["interior"] = s.interior;
    worst.push_back(w);
  }
  rep["worst"] = worst;
  // Where the interior maximum stands (the place to look first, passing or not).
  std::size_t highest = res.samples.size();
  for (std::size_t i = 0; i < res.samples.size(); ++i) {
    const SimSample& s = res.samples[i];
    if (s.interior && !std::isnan(s.scallop) && (highest == res.samples.size() || s.scallop > res.samples[highest].scallop))
      highest = i;
  }
  if (highest < res.samples.size())
    rep["scallop_max_interior_at"] = xyz(Eigen::Vector3d(res.samples[highest].x, res.samples[highest].y, res.samples[highest].z));

  nlohmann::json reasons = nlohmann::json::array();
  char buf[400];
  if (!std::isfinite(max_inner)) {
    reasons.push_back("no interior sample was cut");
  } else if (max_inner > 1.01 * H) {
    // where, and how much of the part: a few places between the samples or whole faces
    const SimSample& at = res.samples[highest];
    const double spacing_area = measured > 0 && n_measured > 0 ? measured / double(n_measured) : 0;
    char extent[160];
    if (over > 0)
      std::snprintf(extent, sizeof extent, "%.4g mm² over 1.01 H or uncut, %.3g %% of the measured area", over,
                    100 * over / measured);
    else
      std::snprintf(extent, sizeof extent, "between the samples: less than one sample's area (%.3g mm²) over 1.01 H",
                    spacing_area);
    std::snprintf(buf, sizeof buf, "interior scallop max %.4g > 1.01 H (whole part %.4g) at (%.3f, %.3f, %.3f); %s",
                  max_inner, max_all, at.x, at.y, at.z, extent);
    std::string reason = buf;
    // (the rest search keeps its unreached places 2 r apart: one stands for what lies around it)
    const Eigen::Vector3d where(at.x, at.y, at.z);
    if (std::any_of(o.unreached_at.begin(), o.unreached_at.end(),
                    [&](const Eigen::Vector3d& q) { return (q - where).norm() <= 2 * r; })) {
      std::snprintf(buf, sizeof buf,
                    o.unreached_by_any_direction
                        ? "; no clamping's axis comes down to it clear of the part, nor any direction the rest search "
                          "tried (%.3g mm² such, post.setup_programs): not for this tool on a 3-axis machine"
                        : "; no clamping's axis comes down to it clear of the part (%.3g mm² such, "
                          "post.setup_programs): another clamping would (rest_setups)",
                    o.unreached_area);
      reason += buf;
    }
    reasons.push_back(reason);
  }
  if (gouge_max > tol) {
    std::snprintf(buf, sizeof buf, "gouge max %.4g > %.4g", gouge_max, tol);
    reasons.push_back(buf);
  }
  if (cloud_deepest.first > tol) {
    std::snprintf(buf, sizeof buf, "%zu point(s) of the cloud inside a ball, up to %.4g deep at (%.3f, %.3f, %.3f)",
                  cloud_cut, cloud_deepest.first, cloud_deepest.second.x(), cloud_deepest.second.y(),
                  cloud_deepest.second.z());
    reasons.push_back(buf);
  }
  if (unbounded_points > 0) {
    std::snprintf(buf, sizeof buf,
                  "%zu point(s) of the cloud outside the outer mesh, up to %.4g mm at (%.3f, %.3f, %.3f), with a ball "
                  "passing within r + that: the gouge there is not bounded",
                  unbounded_points, unbounded.first, unbounded.second.x(), unbounded.second.y(), unbounded.second.z());
    reasons.push_back(buf);
  }
  if (tangle_samples_reached > 0) {
    std::snprintf(buf, sizeof buf,
                  "the part's mesh crosses itself (%zu face pairs, %zu faces tangled) and balls pass within %.3g mm of "
                  "those faces, nearest at (%.3f, %.3f, %.3f): the part there is not known, the gouge there is not bounded",
                  crossings.pairs.size(), crossings.tangled.size(), 0.75 * keep.margin, tangle_nearest.second.x(),
                  tangle_nearest.second.y(), tangle_nearest.second.z());
    reasons.push_back(buf);
  }
  if (measured <= 0) {
    reasons.push_back("nothing to measure: every sample is base or unreachable");
  } else if (uncut > 0) {
    std::snprintf(buf, sizeof buf, "uncut fraction %.4g > 0", uncut / measured);
    reasons.push_back(buf);
  }
  if (through_total > 0) reasons.push_back(std::to_string(through_total) + " rapid(s) through the part");
  rep["pass"] = reasons.empty();
  rep["fail_reasons"] = reasons;
  if (progress) progress(1.0);
  return res;
}

}  // namespace scallop
