#include "nodes/post/rest_passes.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <optional>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/path/step_size.h"
#include "nodes/post/centre_index.h"
#include "nodes/post/keep_off_part.h"
#include "nodes/post/part_samples.h"

namespace scallop {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The ball-centre segments of a setup's passes (machine frame), taken back to the part's frame.
void part_frame_centres(const Setup& s, const std::vector<ToolpathPass>& passes, double r,
                        std::vector<CentreSegment>& out) {
  for (const ToolpathPass& p : passes) {
    Eigen::Vector3d prev;
    for (std::size_t k = 0; k < p.contact.size(); ++k) {
      const Eigen::Vector3d c = s.rotation.transpose() * (p.contact[k] + r * p.normal[k] - s.translation);
      if (k > 0 || p.contact.size() == 1) out.push_back({k > 0 ? prev : c, c});
      prev = c;
    }
  }
}

// The material over each sample left by the cut (NaN: uncut), traced as post.simulate_part does.
void trace_left(const std::vector<PartSample>& samples, const std::vector<PartTriangle>& tris,
                const std::vector<std::uint32_t>& which, const std::vector<CentreSegment>& feed, double spacing,
                double r, double T, std::vector<double>& scallop) {
  if (feed.empty()) return;
  const CentreIndex index(feed, centre_piece_length(feed, spacing, r));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, which.size(), 256), [&](const auto& range) {
    std::vector<std::uint32_t> scratch;
    for (std::size_t k = range.begin(); k < range.end(); ++k) {
      const PartSample& s = samples[which[k]];
      double gouge = 0, left = std::numeric_limits<double>::quiet_NaN();
      index.trace(s.p, tris[s.tri].n, r, T, 0, gouge, left, scratch);
      double& old = scallop[which[k]];
      if (std::isnan(old) || (!std::isnan(left) && left < old)) old = left;
    }
  });
}

}  // namespace

RestResult add_rest_passes(const Mesh& part, std::vector<Setup>& setups, std::vector<Toolpath>& cuts,
                           const RestOptions& o, const MeshDistance* part_distance) {
  const double r = o.tool_radius, H = o.scallop;
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(H > 0) || !(H < r)) throw std::invalid_argument("the scallop limit must be > 0 and below the tool radius");
  if (cuts.size() != setups.size()) throw std::invalid_argument("one cut per setup is needed");
  RestResult res;
  res.passes.assign(setups.size(), 0);
  res.length.assign(setups.size(), 0);
  const std::vector<PartTriangle> tris = part_triangles(part);
  if (o.rounds <= 0 || tris.empty() || setups.empty()) return res;

  const double tol_reach = std::max(o.chord, 1e-3);                 // verify_part.py's
  const double tol_keep = part_clearance_tolerance(o.chord);        // how near balls are kept
  const double nominal = std::sqrt(8 * r * H), T = 20 * H, limit = 0.8 * H;
  res.spacing = part_sample_spacing(tris, nominal / 6, o.max_samples);
  std::vector<PartSample> samples = sample_part(tris, res.spacing);
  const std::optional<MeshDistance> own = part_distance ? std::nullopt : std::optional<MeshDistance>(std::in_place, part);
  const MeshDistance& distance = part_distance ? *part_distance : *own;
  const auto progress = [&](double f, const std::string& what) {
    if (o.progress) o.progress(f, what);
  };
  progress(0, "what the passes leave");

  // Samples measured (not base, reachable) and what the setups' own passes leave there.
  const bool has_base = o.base_normal.norm() > 0;
  const Eigen::Vector3d base_n = has_base ? Eigen::Vector3d(o.base_normal.normalized()) : Eigen::Vector3d::Zero();
  const double cos_base = std::cos(o.base_angle * kPi / 180);
  // 1 measured; 2 out of reach of a ball of radius r but not of 0.9 r: beside a concave edge the
  // band a ball reaches is thin and may hold no sample of the grid, yet the material left in it
  // is high (post.simulate_part seeds its refinement there too; the block kept 0.044 mm).
  std::vector<char> measured(samples.size(), 0);
  tbb::parallel_for(std::size_t(0), samples.size(), [&](std::size_t i) {
    const Eigen::Vector3d& n = tris[samples[i].tri].n;
    if (has_base && n.dot(base_n) >= cos_base) return;
    measured[i] = ball_reaches(distance, samples[i].p, n, r, tol_reach) ? 1
                  : ball_reaches(distance, samples[i].p, n, 0.9 * r, tol_reach) ? 2
                                                                               : 0;
  });
  std::vector<std::uint32_t> left;
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (measured[i] == 1) left.push_back(std::uint32_t(i)), res.measured_area += samples[i].weight;
  std::vector<double> scallop(samples.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<CentreSegment> feed;
  for (std::size_t s = 0; s < setups.size(); ++s) part_frame_centres(setups[s], cuts[s].passes, r, feed);
  trace_left(samples, tris, left, feed, res.spacing, r, T, scallop);
  // Between samples the material may stand higher than at them (a cusp's crest between two rows
  // falls off about as fast as the rows are apart over r): around every sample over 0.65 h, a 5 x 5
  // grid a fifth of the spacing apart (in its triangle) is traced too, sharing its area.
  std::vector<std::uint32_t> root(samples.size());  // a refinement sample's seed; the others themselves
  std::iota(root.begin(), root.end(), std::uint32_t(0));
  {
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t i : left)
      if (std::isnan(scallop[i]) || scallop[i] > 0.65 * H) seeds.push_back(i);
    // ... and around the highest of the others (3000, or 1 % of them on a large part), as the
    // certificate refines its highest.
    std::vector<std::uint32_t> others;
    for (std::uint32_t i : left)
      if (!(std::isnan(scallop[i]) || scallop[i] > 0.65 * H)) others.push_back(i);
    const std::size_t highest_others = std::max<std::size_t>(3000, others.size() / 100);
    if (others.size() > highest_others) {
      std::nth_element(others.begin(), others.begin() + std::ptrdiff_t(highest_others), others.end(),
                       [&](std::uint32_t a, std::uint32_t b) { return scallop[a] > scallop[b]; });
      others.resize(highest_others);
    }
    seeds.insert(seeds.end(), others.begin(), others.end());
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (measured[i] == 2) seeds.push_back(std::uint32_t(i));
    std::vector<PartSample> extra;
    for (std::uint32_t i : seeds) {
      const PartSample& seed = samples[i];
      const PartTriangle& t = tris[seed.tri];
      const Eigen::Vector3d e1 = (t.b - t.a).normalized(), e2 = t.n.cross(e1);
      const std::size_t from = extra.size();
      for (int a = -2; a <= 2; ++a)
        for (int b = -2; b <= 2; ++b) {
          const Eigen::Vector3d p = seed.p + res.spacing * (a * e1 + b * e2) / 5;
          // (a band seed is out of the ball's reach: its samples that are not are their own roots)
          if ((a != 0 || b != 0) && in_part_triangle(t, p))
            root.push_back(measured[i] == 2 ? std::uint32_t(samples.size() + extra.size()) : i),
                extra.push_back({p, 0, seed.tri});
        }
      const double share = seed.weight / double(extra.size() - from + 1);
      samples[i].weight = share;
      for (std::size_t k = from; k < extra.size(); ++k) extra[k].weight = share;
    }
    // Only the refinement samples a ball reaches are measured (as the certificate classifies its own).
    std::vector<char> reached(extra.size(), 0);
    tbb::parallel_for(std::size_t(0), extra.size(), [&](std::size_t k) {
      reached[k] = ball_reaches(distance, extra[k].p, tris[extra[k].tri].n, r, tol_reach);
    });
    std::vector<std::uint32_t> which;
    for (std::size_t k = 0; k < extra.size(); ++k)
      if (reached[k]) {
        which.push_back(std::uint32_t(samples.size() + k));
        if (root[samples.size() + k] == samples.size() + k) res.measured_area += extra[k].weight;  // a band's
      }
    samples.insert(samples.end(), extra.begin(), extra.end());
    scallop.resize(samples.size(), std::numeric_limits<double>::quiet_NaN());
    trace_left(samples, tris, which, feed, res.spacing, r, T, scallop);
    left.insert(left.end(), which.begin(), which.end());
  }
  auto still_left = [&](std::uint32_t i) { return std::isnan(scallop[i]) || scallop[i] > limit; };
  auto area_of = [&](const std::vector<std::uint32_t>& list) {
    double a = 0;
    for (std::uint32_t i : list) a += samples[i].weight;
    return a;
  };
  left.erase(std::remove_if(left.begin(), left.end(), [&](std::uint32_t i) { return !still_left(i); }), left.end());
  res.left_area_before = area_of(left);

  // Each left place's setup: the largest n . a whose axis comes down to it clear of the part,
  // found for the grid's samples (a refinement sample takes its seed's).
  std::vector<Eigen::Vector3d> axis;
  std::vector<double> highest;  // the part's highest point along each axis
  auto add_axis = [&](const Eigen::Vector3d& a) {
    axis.push_back(a);
    highest.push_back(-INFINITY);
    for (const auto& v : part.vertices) highest.back() = std::max(highest.back(), v.dot(a));
  };
  for (const Setup& s : setups) add_axis(s.rotation.row(2).transpose());  // the machine's +z in the part's frame
  // Whether the ball tangent at sample i goes straight up along axis s clear of the part.
  auto comes_down = [&](std::uint32_t i, std::size_t s) {
    const Eigen::Vector3d& n = tris[samples[i].tri].n;
    if (!(n.dot(axis[s]) >= o.min_normal_dot)) return false;
    const Eigen::Vector3d c = samples[i].p + r * n;
    if (std::isfinite(distance.ray_distance(c, axis[s]))) return false;  // its centre line meets the part
    // a ball of r - tol_keep coming down the axis from above the part touches it nowhere above c
    const double rise = highest[s] - c.dot(axis[s]) + r + 1;
    if (!(rise > 0)) return distance(c) >= r - tol_keep;
    return distance.touch_along(c + rise * axis[s], -axis[s], r - tol_keep, rise) >= rise;
  };
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> roots;
  for (std::uint32_t i : left) roots.push_back(root[i]);
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  // setup_at: the setup that comes down clear; nearest: the setup facing it best (n . a >= 0.5),
  // whose rows a place no setup comes down to gets, as near as the ball goes.
  std::vector<std::uint32_t> setup_at(samples.size(), kNone), nearest(samples.size(), kNone);
  tbb::parallel_for(std::size_t(0), roots.size(), [&](std::size_t q) {
    const std::uint32_t i = roots[q];
    const Eigen::Vector3d& n = tris[samples[i].tri].n;
    std::vector<std::pair<double, std::uint32_t>> order;
    for (std::size_t s = 0; s < setups.size(); ++s) order.emplace_back(-n.dot(axis[s]), std::uint32_t(s));
    std::sort(order.begin(), order.end());
    if (!order.empty() && -order.front().first >= 0.5) nearest[i] = order.front().second;
    for (const auto& [dot, s] : order)
      if (comes_down(i, s)) {
        setup_at[i] = s;
        break;
      }
  });
  // Places no setup comes down to: new clampings, each along the direction of a 2000-point
  // lattice over the sphere that comes down to the most of them (counted on up to 64 of them,
  // among directions within 60 degrees of their normals), while one comes down to any.
  const std::vector<Eigen::Vector3d> lattice = sphere_lattice(2000);
  for (int added = 0; added < o.max_new_setups; ++added) {
    std::vector<std::uint32_t> unreached;
    for (std::uint32_t i : roots)
      if (setup_at[i] == kNone) unreached.push_back(i);
    if (unreached.empty()) break;
    std::vector<std::uint32_t> probe;
    const std::size_t probes = std::min<std::size_t>(64, unreached.size());
    for (std::size_t q = 0; q < probes; ++q) probe.push_back(unreached[q * unreached.size() / probes]);
    const std::size_t first_axis = axis.size();
    for (const auto& a : lattice) add_axis(a);
    std::vector<std::pair<std::size_t, double>> score(lattice.size(), {0, 0.0});  // places, their sum of n . a
    tbb::parallel_for(std::size_t(0), lattice.size(), [&](std::size_t d) {
      for (std::uint32_t i : probe) {
        const double dot = tris[samples[i].tri].n.dot(lattice[d]);
        if (dot >= 0.5 && comes_down(i, first_axis + d)) ++score[d].first, score[d].second += dot;
      }
    });
    const std::size_t best = std::max_element(score.begin(), score.end()) - score.begin();
    axis.resize(first_axis), highest.resize(first_axis);
    if (score[best].first == 0) {
      res.no_direction_left = true;
      break;
    }
    Setup s;
    s.axis = lattice[best];
    place_setup(s, part.vertices);  // as surface.setups places its setups
    char name[96];
    std::snprintf(name, sizeof name, "%zu: rest (%.3f, %.3f, %.3f)", setups.size() + 1, s.axis.x(), s.axis.y(), s.axis.z());
    s.name = name;
    s.min_normal_dot = 0.5;
    setups.push_back(s);
    Toolpath cut;
    cut.tool_radius = r, cut.scallop_height = H, cut.chord_error = o.chord, cut.pattern = "rest";
    cuts.push_back(cut);
    res.passes.push_back(0), res.length.push_back(0);
    add_axis(s.axis);
    ++res.new_setups;
    tbb::parallel_for(std::size_t(0), unreached.size(), [&](std::size_t q) {
      if (comes_down(unreached[q], setups.size() - 1)) setup_at[unreached[q]] = std::uint32_t(setups.size() - 1);
    });
  }
  std::vector<std::uint32_t> setup_of(left.size());
  for (std::size_t k = 0; k < left.size(); ++k) {
    const std::uint32_t i = root[left[k]];
    setup_of[k] = setup_at[i] != kNone ? setup_at[i] : nearest[i];
  }

  for (int round = 0; round < o.rounds && !left.empty(); ++round) {
    std::vector<CentreSegment> added;
    for (std::size_t s = 0; s < setups.size(); ++s) {
      progress(0.2 + 0.8 * (round + double(s) / setups.size()) / o.rounds,
               "rest round " + std::to_string(round + 1) + ", setup " + std::to_string(s + 1) + " of " +
                   std::to_string(setups.size()));
      const Setup& setup = setups[s];
      std::vector<Eigen::Vector3d> targets;  // ball centres, machine frame
      double least_nz = 1;
      for (std::size_t k = 0; k < left.size(); ++k) {
        if (setup_of[k] != s || !still_left(left[k])) continue;
        const PartSample& sample = samples[left[k]];
        const Eigen::Vector3d n = setup.rotation * tris[sample.tri].n;
        targets.push_back(setup.rotation * sample.p + setup.translation + r * n);
        least_nz = std::min(least_nz, n.z());
      }
      if (targets.empty()) continue;
      const double pitch = 0.9 * nominal * std::max(0.25, least_nz) / double(1 << round);
      const double step = std::min(pitch, std::sqrt(8 * r * tol_keep));
      // The raster's cells within a pitch of a target's centre.
      std::vector<std::pair<long, long>> cells;  // (row, column)
      for (const Eigen::Vector3d& c : targets)
        for (long j = long(std::ceil((c.y() - pitch) / pitch)); j <= long(std::floor((c.y() + pitch) / pitch)); ++j)
          for (long i = long(std::ceil((c.x() - pitch - step) / step)); i <= long(std::floor((c.x() + pitch + step) / step));
               ++i)
            cells.emplace_back(j, i);
      std::sort(cells.begin(), cells.end());
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());

      Mesh placed = part;
      for (auto& v : placed.vertices) v = setup.rotation * v + setup.translation;
      double top_z = -INFINITY, bottom_z = INFINITY;
      for (const auto& v : placed.vertices) top_z = std::max(top_z, v.z()), bottom_z = std::min(bottom_z, v.z());
      const MeshDistance placed_distance = distance.placed(setup.rotation, setup.translation);
      const std::vector<Eigen::Vector3d> placed_normal = face_geometry(placed).normal;
      // Each cell's ball dropped from above the part; kept where it touches the part from the
      // outside of the face it touches (through a hole in the mesh, a ball would fall onto the
      // inside of the part's far side: a cloud's reconstruction has holes). On an edge the nearest
      // face may be the one the ball's direction is square to: 0 counts as outside.
      std::vector<Eigen::Vector3d> centre(cells.size());
      std::vector<char> touches(cells.size(), 0);
      std::atomic<std::size_t> inside_drops{0};
      tbb::parallel_for(std::size_t(0), cells.size(), [&](std::size_t q) {
        Eigen::Vector3d c(cells[q].second * step, cells[q].first * pitch, top_z + r + 1);
        drop_onto(c, placed_distance, r, top_z - bottom_z + 2 * r + 2);
        centre[q] = c;
        const Eigen::Vector3d contact = placed_distance.closest_point(c);
        touches[q] = std::abs((c - contact).norm() - r) <= 1e-3 &&
                     (c - contact).dot(placed_normal[placed_distance.closest_face(c)]) > -1e-6 * r;
        if (std::abs((c - contact).norm() - r) <= 1e-3 && !touches[q]) ++inside_drops;
      });
      res.inside_drops += inside_drops;
      Toolpath rest;
      rest.tool_radius = r, rest.scallop_height = H, rest.chord_error = o.chord, rest.pattern = "rest";
      for (std::size_t q = 0; q < cells.size();) {
        std::size_t end = q + 1;  // a run of neighbouring cells of one row
        while (end < cells.size() && cells[end].first == cells[q].first && cells[end].second == cells[end - 1].second + 1)
          ++end;
        ToolpathPass pass;
        for (std::size_t k = q; k <= end; ++k) {
          if (k < end && touches[k]) {
            const Eigen::Vector3d contact = placed_distance.closest_point(centre[k]);
            const Eigen::Vector3d n = (centre[k] - contact).normalized();
            if (n.allFinite()) {
              pass.contact.push_back(centre[k] - r * n), pass.normal.push_back(n);
              continue;
            }
          }
          if (!pass.contact.empty()) {
            if (cells[q].first % 2 != 0) {  // every other row the other way: a zig-zag
              std::reverse(pass.contact.begin(), pass.contact.end());
              std::reverse(pass.normal.begin(), pass.normal.end());
            }
            rest.passes.push_back(std::move(pass));
            pass = ToolpathPass();
          }
        }
        q = end;
      }
      if (rest.passes.empty()) continue;
      // A run that starts within two pitches of where the one before it ends (the next row of a
      // zig-zag) continues it: one pass, not a retract and a plunge per row. The move between
      // them is kept off the part like any other.
      std::vector<ToolpathPass> joined;
      for (ToolpathPass& p : rest.passes) {
        auto ball = [&](const ToolpathPass& q, std::size_t k) { return Eigen::Vector3d(q.contact[k] + r * q.normal[k]); };
        if (!joined.empty() && (ball(joined.back(), joined.back().contact.size() - 1) - ball(p, 0)).norm() <= 2 * pitch) {
          joined.back().contact.insert(joined.back().contact.end(), p.contact.begin(), p.contact.end());
          joined.back().normal.insert(joined.back().normal.end(), p.normal.begin(), p.normal.end());
        } else {
          joined.push_back(std::move(p));
        }
      }
      rest.passes = std::move(joined);
      keep_off_part(rest, {}, placed_distance, top_z, tol_keep);
      res.passes[s] += rest.passes.size();
      const std::size_t from = added.size();
      part_frame_centres(setup, rest.passes, r, added);
      for (std::size_t k = from; k < added.size(); ++k) res.length[s] += (added[k].b - added[k].a).norm();
      for (auto& p : rest.passes) cuts[s].passes.push_back(std::move(p));
    }
    if (added.empty()) break;
    ++res.rounds;
    const double before = area_of(left);
    trace_left(samples, tris, left, added, res.spacing, r, T, scallop);
    std::vector<std::uint32_t> kept, kept_setup;
    for (std::size_t k = 0; k < left.size(); ++k)
      if (still_left(left[k])) kept.push_back(left[k]), kept_setup.push_back(setup_of[k]);
    left.swap(kept), setup_of.swap(kept_setup);
    if (area_of(left) > 0.9 * before) break;
  }
  res.left_area_after = area_of(left);
  for (std::uint32_t i : left) {
    if (setup_at[root[i]] != kNone) continue;
    res.unreached_area += samples[i].weight;
    const Eigen::Vector3d& p = samples[i].p;
    if (res.unreached_at.size() < 10 &&
        std::none_of(res.unreached_at.begin(), res.unreached_at.end(), [&](const auto& q) { return (q - p).norm() < 2 * r; }))
      res.unreached_at.push_back(p);
  }
  return res;
}

}  // namespace scallop
