#include "nodes/post/surface_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "nodes/geom/outline.h"
#include "nodes/path/step_size.h"

namespace scallop {

SurfaceSamples sample_surface_grid(const HeightFieldModel& surf, const SurfaceGridOptions& o,
                                   const std::function<void(double)>& progress) {
  const double r = o.tool_radius, H = o.scallop;
  if (!(r > 0)) throw std::invalid_argument("tool radius must be > 0");
  if (!(H > 0)) throw std::invalid_argument("scallop limit must be > 0");
  const bool use_loops = !o.loops.empty();
  if (use_loops) {
    if (o.loops[0].size() < 3)
      throw std::invalid_argument("the outer loop has " + std::to_string(o.loops[0].size()) +
                                  " points; an outline needs at least 3");
    for (const auto& L : o.loops)
      for (const auto& q : L)
        if (!q.allFinite()) throw std::invalid_argument("a loop has a non-finite point");
  }
  SurfaceSamples out;
  out.options = o;
  out.cloud_points = surf.points().size();
  double spacing = o.spacing > 0 ? o.spacing : std::sqrt(8 * r * H) / 12;
  {
    // Keep the grid over the cloud's bounding box within max_samples.
    double area = (surf.max_x() - surf.min_x()) * (surf.max_y() - surf.min_y());
    if (o.spacing <= 0 && area / (spacing * spacing) > double(o.max_samples))
      spacing = std::sqrt(area / double(o.max_samples));
  }
  // The grid covers the cloud's bounding box, centred on it.
  out.spacing = spacing;
  out.cx = 0.5 * (surf.min_x() + surf.max_x()), out.cy = 0.5 * (surf.min_y() + surf.max_y());
  out.extent = 0.5 * std::hypot(surf.max_x() - surf.min_x(), surf.max_y() - surf.min_y()) + 3 * spacing;
  const int nu = out.nodes = static_cast<int>(std::ceil(2 * out.extent / spacing));
  const GridFrame g = grid_frame(out);
  const double cx = out.cx, cy = out.cy, ca = g.ca, sa = g.sa, Rg = out.extent;

  // Which grid nodes fall on the patch; holes in the cloud (not connected to the outside of the
  // grid through other missing nodes) are part of the patch too.
  std::vector<std::uint8_t>& inside = out.inside;
  inside.assign(std::size_t(nu) * nu, 0);
  if (use_loops) {
    // Scanline fill with the even-odd rule over all loops at once (inside the outer loop and
    // outside the holes): per grid row, the u where each polygon edge crosses the row's v,
    // sorted; grid nodes between the 1st and 2nd, 3rd and 4th ... crossing are inside.
    std::vector<std::array<double, 4>> edges;  // (u0, v0, u1, v1) in grid coordinates
    for (const auto& L : o.loops)
      for (std::size_t k = 0; k < L.size(); ++k) {
        const Eigen::Vector2d a = L[k] - Eigen::Vector2d(cx, cy), b = L[(k + 1) % L.size()] - Eigen::Vector2d(cx, cy);
        edges.push_back({ca * a.x() + sa * a.y(), -sa * a.x() + ca * a.y(), ca * b.x() + sa * b.y(), -sa * b.x() + ca * b.y()});
      }
    tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
      std::vector<double> cross;
      for (int j = rg.begin(); j < rg.end(); ++j) {
        const double v = g.v(j);
        cross.clear();
        for (const auto& e : edges)
          if ((e[1] <= v) != (e[3] <= v)) cross.push_back(e[0] + (v - e[1]) / (e[3] - e[1]) * (e[2] - e[0]));
        std::sort(cross.begin(), cross.end());
        for (std::size_t c = 0; c + 1 < cross.size(); c += 2) {
          // g.u(i) = -Rg + (i + kGridPhaseU) spacing; nodes with cross[c] <= u < cross[c+1]
          const int i0 = std::max(0, static_cast<int>(std::ceil((cross[c] + Rg) / spacing - kGridPhaseU)));
          const int i1 = std::min(nu - 1, static_cast<int>(std::ceil((cross[c + 1] + Rg) / spacing - kGridPhaseU)) - 1);
          for (int i = i0; i <= i1; ++i) inside[std::size_t(j) * nu + i] = 1;
        }
      }
    });
  } else {
    tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
      for (int j = rg.begin(); j < rg.end(); ++j)
        for (int i = 0; i < nu; ++i) {
          Eigen::Vector2d q = g.xy(g.u(i), g.v(j));
          if (q.x() < surf.min_x() - spacing || q.x() > surf.max_x() + spacing || q.y() < surf.min_y() - spacing ||
              q.y() > surf.max_y() + spacing)
            continue;
          inside[std::size_t(j) * nu + i] = surf.inside(q.x(), q.y());
        }
    });
    std::vector<std::uint8_t> outside(inside.size(), 0);
    std::vector<std::size_t> stack;
    for (int i = 0; i < nu; ++i)
      for (std::size_t id : {std::size_t(i), std::size_t(nu - 1) * nu + i, std::size_t(i) * nu, std::size_t(i) * nu + nu - 1})
        if (!inside[id] && !outside[id]) outside[id] = 1, stack.push_back(id);
    while (!stack.empty()) {
      std::size_t id = stack.back();
      stack.pop_back();
      int i = int(id % nu), j = int(id / nu);
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int t = 0; t < 4; ++t) {
        int ii = i + di[t], jj = j + dj[t];
        if (ii < 0 || jj < 0 || ii >= nu || jj >= nu) continue;
        std::size_t nid = std::size_t(jj) * nu + ii;
        if (!inside[nid] && !outside[nid]) outside[nid] = 1, stack.push_back(nid);
      }
    }
    for (std::size_t id = 0; id < inside.size(); ++id) inside[id] = !outside[id];
  }
  if (progress) progress(0.1);

  const double rim_band = !use_loops ? 0.0 : o.rim_band >= 0 ? o.rim_band : certified_rim_band(surf.spacing());
  out.rim_band = rim_band;
  const Outline outline_polygons(rim_band > 0 ? o.loops : std::vector<std::vector<Eigen::Vector2d>>{});
  std::vector<std::vector<SurfacePoint>> rows(nu);
  std::atomic<int> rows_done{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
    for (int j = rg.begin(); j < rg.end(); ++j) {
      for (int i = 0; i < nu; ++i) {
        Eigen::Vector2d q = g.xy(g.u(i), g.v(j));
        double z, u;
        Eigen::Vector3d n;
        if (!inside[std::size_t(j) * nu + i]) {
          // the rim band: within rim_band along the surface of the outer loop, or of a hole's
          if (rim_band <= 0) continue;
          const double d = outline_polygons.beyond(q);
          if (!(d > 0 && d <= rim_band) || !surf.eval(q.x(), q.y(), z, n, true, &u) || d > rim_band * n.z())
            continue;
          inside[std::size_t(j) * nu + i] = 2;
          rows[j].push_back({{q.x(), q.y(), z}, n, spacing * spacing / n.z(), u, true});
          continue;
        }
        if (!surf.eval(q.x(), q.y(), z, n, true, &u)) continue;
        // Steep cells are split k×k so the spacing along the surface stays near `spacing`.
        int k = std::clamp(static_cast<int>(std::lround(1.0 / n.z())), 1, 4);
        if (k == 1) {
          rows[j].push_back({{q.x(), q.y(), z}, n, spacing * spacing / n.z(), u, false});
          continue;
        }
        for (int a = 0; a < k; ++a)
          for (int b = 0; b < k; ++b) {
            Eigen::Vector2d s = g.xy(g.u(i) + ((a + 0.5) / k - 0.5) * spacing, g.v(j) + ((b + 0.5) / k - 0.5) * spacing);
            double zs, us;
            Eigen::Vector3d ns;
            if (surf.eval(s.x(), s.y(), zs, ns, true, &us))
              rows[j].push_back({{s.x(), s.y(), zs}, ns, spacing * spacing / (k * k * ns.z()), us, false});
          }
      }
      const int done = ++rows_done;
      if (progress && done % 64 == 0) progress(0.1 + 0.85 * double(done) / nu);
    }
  });
  out.row_start.assign(nu + 1, 0);
  for (int j = 0; j < nu; ++j) out.row_start[j + 1] = out.row_start[j] + rows[j].size();
  if (out.row_start[nu] == 0) throw std::invalid_argument("no grid sample falls on the surface");
  out.points.resize(out.row_start[nu]);
  tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& rg) {
    for (int j = rg.begin(); j < rg.end(); ++j) {
      std::copy(rows[j].begin(), rows[j].end(), out.points.begin() + std::ptrdiff_t(out.row_start[j]));
      std::vector<SurfacePoint>().swap(rows[j]);
    }
  });
  for (const SurfacePoint& s : out.points) out.uncertainty_max = std::max(out.uncertainty_max, s.uncertainty);
  if (progress) progress(1.0);
  return out;
}

}  // namespace scallop
