#include "nodes/post/keep_off_part.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace scallop {

double lift_clear(Eigen::Vector3d& c, const MeshDistance& part, double r, double tolerance) {
  double lift = 0;
  for (int it = 0; it < 400; ++it) {
    const double d = part(c);
    double step = 0;
    if (d < r - tolerance)
      step = r - d + 1e-6;  // the surface is no nearer than d: at least this far to clear
    else if (const double above = part.ray_distance(c, Eigen::Vector3d::UnitZ()); std::isfinite(above))
      step = above + r;  // over the face above, then again
    else
      break;
    c.z() += step;
    lift += step;
  }
  return lift;
}

double drop_onto(Eigen::Vector3d& c, const MeshDistance& part, double r, double max_drop) {
  const double drop = part.touch_along(c, -Eigen::Vector3d::UnitZ(), r, max_drop);
  c.z() -= drop;
  return drop;
}

std::vector<ToolpathPass> keep_pass_off_part(ToolpathPass pass, double r, const MeshDistance& part, double part_top_z,
                                             double tolerance, double max_drop, KeepOffStats& stats) {
  // A pass's ends: the tool comes down onto its start and leaves its end straight along +z, so the
  // ball must pass the part on the way, not only its centre line (a compound-angle clamping put
  // an overhang 0.33 mm into a ball plunging onto a fandisk contour): the end is raised to the
  // lowest height from which the vertical up to above the part stays r - tolerance off it: where
  // a ball of that radius coming down from above the part first touches it (one ray,
  // MeshDistance::touch_along; a bisection of clear_along's before stop 62).
  const double top = part_top_z + r + 1;
  // How far below `top` a ball of radius r - tolerance coming down at (x, y) of c first touches
  // the part (up to `down`).
  auto touch_from_top = [&](const Eigen::Vector3d& c, double down) {
    return part.touch_along(Eigen::Vector3d(c.x(), c.y(), top), -Eigen::Vector3d::UnitZ(), r - tolerance, down);
  };
  // Whether the ball goes straight up clear from centre height z at (x, y) of c.
  auto goes_up_clear = [&](const Eigen::Vector3d& c, double z) { return z >= top || touch_from_top(c, top - z) >= top - z; };
  auto clear_above = [&](Eigen::Vector3d& contact, const Eigen::Vector3d& n) {
    const Eigen::Vector3d c = contact + r * n;
    if (c.z() >= top) return;
    const double touch = touch_from_top(c, top - c.z());
    if (touch >= top - c.z()) return;
    const double rise = (top - touch) - c.z() + 1e-9;  // the touching height, up from where rounding may leave it
    contact.z() += rise;
    ++stats.lifted;
    stats.lift_max = std::max(stats.lift_max, rise);
  };
  // The ball at contact lifted clear; returns the lift.
  auto lift_point = [&](Eigen::Vector3d& contact, const Eigen::Vector3d& n) {
    Eigen::Vector3d c = contact + r * n;
    const double lift = lift_clear(c, part, r, tolerance);
    if (lift > 0) contact = c - r * n;
    return lift;
  };
  auto count_lift = [&](double lift) {
    if (!(lift > 0)) return;
    ++stats.lifted;
    stats.lift_max = std::max(stats.lift_max, lift);
  };
  // Each ball lowered and lifted on its own: side by side (a rest raster joined into one pass
  // holds thousands), counted after.
  const std::vector<Eigen::Vector3d> planned = pass.contact;  // before any lift, for the report
  std::vector<double> drops(pass.contact.size(), 0), lifts(pass.contact.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pass.contact.size(), 32), [&](const auto& range) {
    for (std::size_t k = range.begin(); k < range.end(); ++k) {
      if (max_drop > 0) {
        Eigen::Vector3d c = pass.contact[k] + r * pass.normal[k];
        if (const double drop = drop_onto(c, part, r, max_drop); drop > 0) pass.contact[k] = c - r * pass.normal[k], drops[k] = drop;
      }
      lifts[k] = lift_point(pass.contact[k], pass.normal[k]);
    }
  });
  for (std::size_t k = 0; k < pass.contact.size(); ++k) {
    if (drops[k] > 0) ++stats.lowered, stats.lower_max = std::max(stats.lower_max, drops[k]);
    count_lift(lifts[k]);
  }
  if (!pass.contact.empty()) {
    clear_above(pass.contact.front(), pass.normal.front());
    clear_above(pass.contact.back(), pass.normal.back());
  }
  ToolpathPass out;
  constexpr std::size_t kMiddle = SIZE_MAX;
  std::vector<std::size_t> origin;  // per ball of out: the pass's ball it is, or kMiddle (a move middle)
  // How far the move between ball centres ca and cb must go up: what it lacks in distance, or,
  // where a point of it lies under the part, what that point needs to clear it; 0 when clear.
  auto lacks = [&](const Eigen::Vector3d& ca, const Eigen::Vector3d& cb) {
    Eigen::Vector3d nearest;
    const double least = part.least_on_segment(ca, cb, nearest);
    double need = least < r - tolerance ? r - tolerance - least : 0;
    // Its points are r - tolerance off the part here; one under it (inside the solid or under an
    // overhang: the unsigned distance alone misses a centre deep inside) is not clear either.
    for (int q = 1; q < 8 && need == 0; ++q) {
      Eigen::Vector3d c = ca + (cb - ca) * (q / 8.0);
      if (std::isfinite(part.ray_distance(c, Eigen::Vector3d::UnitZ()))) need = lift_clear(c, part, r, tolerance);
    }
    return need;
  };
  // Balls put in the middle of a move that comes too near the part, or passes under it, in order
  // into `m`; true when the move was found clear as it is (lacks() would say 0: the same test).
  struct Middles {
    bool as_is = false;
    std::vector<Eigen::Vector3d> contact, normal;
    std::vector<double> lifts;
  };
  std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&, const Eigen::Vector3d&, const Eigen::Vector3d&,
                     int, Middles&)>
      middle = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& na, const Eigen::Vector3d& b,
                   const Eigen::Vector3d& nb, int depth, Middles& into) {
        if (depth == 0) return false;
        const Eigen::Vector3d ca = a + r * na, cb = b + r * nb;
        // Where the move comes nearest the part, if nearer than r - tolerance (found exactly,
        // MeshDistance::least_on_segment, unsigned: the part may be open); else where a point of
        // it lies under the part.
        double q = -1;
        Eigen::Vector3d nearest;
        if (part.least_on_segment(ca, cb, nearest) < r - tolerance) {
          const double len2 = (cb - ca).squaredNorm();
          q = len2 > 0 ? std::clamp((nearest - ca).dot(cb - ca) / len2, 1.0 / 16, 15.0 / 16) : 0.5;
        } else {
          for (double f : {0.5, 0.25, 0.75, 0.125, 0.375, 0.625, 0.875})
            if (std::isfinite(part.ray_distance((1 - f) * ca + f * cb, Eigen::Vector3d::UnitZ()))) {
              q = f;
              break;
            }
        }
        if (q < 0) return true;
        const Eigen::Vector3d n = ((1 - q) * na + q * nb).normalized();
        if (!n.allFinite()) return false;
        Eigen::Vector3d m = (1 - q) * ca + q * cb - r * n;
        const double lift = lift_point(m, n);
        middle(a, na, m, n, depth - 1, into);
        into.contact.push_back(m), into.normal.push_back(n), into.lifts.push_back(lift);
        middle(m, n, b, nb, depth - 1, into);
        return false;
      };
  // Each move's middles on its own, side by side; then the balls and middles in order.
  std::vector<Middles> middles(pass.contact.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(1, std::max<std::size_t>(pass.contact.size(), 1), 16),
                    [&](const auto& range) {
                      for (std::size_t k = range.begin(); k < range.end(); ++k)
                        middles[k].as_is = middle(pass.contact[k - 1], pass.normal[k - 1], pass.contact[k],
                                                  pass.normal[k], 6, middles[k]);
                    });
  std::vector<char> clear(1, 0);  // move k-1 -> k found clear, its ends not moved since
  for (std::size_t k = 0; k < pass.contact.size(); ++k) {
    const Middles& m = middles[k];
    for (std::size_t i = 0; i < m.contact.size(); ++i) {
      count_lift(m.lifts[i]);
      out.contact.push_back(m.contact[i]), out.normal.push_back(m.normal[i]), origin.push_back(kMiddle);
      if (!pass.uv.empty()) out.uv.push_back(out.uv.back());
    }
    clear.resize(out.contact.size() + 1, 0);
    clear.back() = k > 0 && m.as_is;
    out.contact.push_back(pass.contact[k]), out.normal.push_back(pass.normal[k]), origin.push_back(k);
    if (!pass.uv.empty()) out.uv.push_back(pass.uv[k]);
  }
  // Where a move still reaches in (a narrow neck above a free pocket: its ends clear, its
  // middle not), its lower end is raised to its upper end's height, until no move does.
  // A sweep checks the moves next to a point the previous one raised (the first, all that the
  // middles did not find clear).
  clear.resize(out.contact.size(), 0);
  std::vector<char> check(out.contact.size()), next(out.contact.size(), 0);  // move k-1 -> k
  for (std::size_t k = 0; k < check.size(); ++k) check[k] = !clear[k];
  for (int sweep = 0; sweep < 50; ++sweep) {
    bool raised = false;
    std::fill(next.begin(), next.end(), 0);
    for (std::size_t k = 1; k < out.contact.size(); ++k) {
      if (!check[k]) continue;
      const Eigen::Vector3d ca = out.contact[k - 1] + r * out.normal[k - 1], cb = out.contact[k] + r * out.normal[k];
      const double need = lacks(ca, cb);
      if (!(need > 0)) {
        clear[k] = 1;
        continue;
      }
      // The lower end goes up to the upper end's height; ends already level (raised so before)
      // both go up by what the move lacks: raising one end to the other's height no longer
      // moves it (a move beside a slope kept 0.01 mm of a fandisk's side that way). So do the ends
      // of a move that lacks less than their height difference: raising the lower end to the
      // upper one's would lift it far more than needed (a move on the domed block's top lacking
      // 0.00007 mm had a ball lifted 0.129 mm, and left a 0.058 mm scallop).
      std::vector<std::size_t> ends;
      double rise;
      if (const double dz = std::abs(cb.z() - ca.z()); dz > 1e-3 && dz <= need) {
        ends = {ca.z() < cb.z() ? k - 1 : k};
        rise = dz + 1e-6;
      } else {
        ends = {k - 1, k};
        rise = std::max(need, 1e-4) + 1e-6;
      }
      for (std::size_t e : ends) {
        out.contact[e].z() += rise;
        count_lift(lift_point(out.contact[e], out.normal[e]));
        ++stats.lifted;
        stats.lift_max = std::max(stats.lift_max, rise);
        next[e] = 1, clear[e] = 0;
        if (e + 1 < next.size()) next[e + 1] = 1, clear[e + 1] = 0;
      }
      raised = true;
    }
    if (!raised) break;
    check.swap(next);
  }
  // Balls lifted more than their radius touch nothing near where they were planned: from this
  // direction the part is in the way there (the walls of the block's bores had whole setups
  // lifted 125 mm over the part). They are counted for the report; the certificate measures the
  // stock they leave. (Leaving them out would also drop the raised ends and the balls over rough
  // ground that keep the tool clear.)
  for (std::size_t k = 0; k < out.contact.size(); ++k) {
    if (origin[k] == kMiddle) continue;
    const double lift = out.contact[k].z() - planned[origin[k]].z();
    if (lift > r) {
      ++stats.high;
      if (lift > stats.high_max) stats.high_max = lift, stats.high_at = planned[origin[k]];
    }
  }
  // What the raising could not clear within its sweeps (a stretch under an overhang, which it
  // climbs over one ball at a time: a fandisk clamping kept a 39 mm vertical move through the
  // part that way) is not cut. The pass is split at every move that still reaches in, and each
  // piece's ends, where the tool comes down and goes up along +z, are trimmed back to balls whose
  // vertical is clear; the linker takes the tool between the pieces above the part.
  std::vector<ToolpathPass> pieces;
  auto centre = [&](std::size_t k) -> Eigen::Vector3d { return out.contact[k] + r * out.normal[k]; };
  auto add_piece = [&](std::size_t first, std::size_t last) {  // balls first..last-1
    const std::size_t balls = last - first;
    while (first < last && !goes_up_clear(centre(first), centre(first).z())) ++first;
    while (last > first && !goes_up_clear(centre(last - 1), centre(last - 1).z())) --last;
    stats.dropped += balls - (last - first);
    if (first == last) return;
    ToolpathPass piece;
    piece.contact.assign(out.contact.begin() + std::ptrdiff_t(first), out.contact.begin() + std::ptrdiff_t(last));
    piece.normal.assign(out.normal.begin() + std::ptrdiff_t(first), out.normal.begin() + std::ptrdiff_t(last));
    if (!out.uv.empty()) piece.uv.assign(out.uv.begin() + std::ptrdiff_t(first), out.uv.begin() + std::ptrdiff_t(last));
    pieces.push_back(std::move(piece));
  };
  std::size_t start = 0;
  for (std::size_t k = 1; k < out.contact.size(); ++k)
    if (!clear[k] && lacks(centre(k - 1), centre(k)) > 0) {
      ++stats.splits;
      add_piece(start, k);
      start = k;
    }
  add_piece(start, out.contact.size());
  return pieces;
}

KeepOffStats keep_off_part(Toolpath& path, const std::vector<double>& max_drop, const MeshDistance& part,
                           double part_top_z, double tolerance) {
  tbb::combinable<KeepOffStats> local;
  std::vector<std::vector<ToolpathPass>> pieces(path.passes.size());
  tbb::parallel_for(std::size_t(0), path.passes.size(), [&](std::size_t i) {
    pieces[i] = keep_pass_off_part(std::move(path.passes[i]), path.tool_radius, part, part_top_z, tolerance,
                                   i < max_drop.size() ? max_drop[i] : 0.0, local.local());
  });
  path.passes.clear();
  for (auto& p : pieces)
    for (auto& piece : p) path.passes.push_back(std::move(piece));
  KeepOffStats stats;
  local.combine_each([&](const KeepOffStats& l) {
    stats.lifted += l.lifted;
    stats.lift_max = std::max(stats.lift_max, l.lift_max);
    stats.dropped += l.dropped;
    stats.splits += l.splits;
    stats.lowered += l.lowered;
    stats.lower_max = std::max(stats.lower_max, l.lower_max);
    stats.high += l.high;
    if (l.high_max > stats.high_max) stats.high_max = l.high_max, stats.high_at = l.high_at;
  });
  return stats;
}

}  // namespace scallop
