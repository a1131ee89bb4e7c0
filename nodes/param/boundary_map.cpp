#include "nodes/param/boundary_map.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "nodes/cloud/boundary_order.h"
#include "nodes/cloud/knn.h"

namespace scallop {

BoundaryDomain parse_boundary_domain(const std::string& name) {
  if (name == "disk") return BoundaryDomain::Disk;
  if (name == "rectangle") return BoundaryDomain::Rectangle;
  throw std::invalid_argument("unknown boundary domain '" + name + "' (disk, rectangle)");
}

namespace {

// cum[i] = chord length from Q[0] to Q[i] along the closed polyline Q; cum[n] = total length L.
std::vector<double> cumulative_lengths(const std::vector<Eigen::Vector3d>& Q) {
  const std::size_t n = Q.size();
  std::vector<double> cum(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) cum[i + 1] = cum[i] + (Q[(i + 1) % n] - Q[i]).norm();
  return cum;
}

// Point at arc length s (any real, taken modulo L) along the closed polyline Q.
Eigen::Vector3d point_at(const std::vector<Eigen::Vector3d>& Q, const std::vector<double>& cum, double s) {
  const std::size_t n = Q.size();
  const double L = cum[n];
  s = std::fmod(s, L);
  if (s < 0) s += L;
  std::size_t i = static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin());
  i = std::clamp<std::size_t>(i, 1, n) - 1;  // segment i: Q[i] -> Q[i+1]
  double seg = cum[i + 1] - cum[i];
  double f = seg > 0 ? (s - cum[i]) / seg : 0.0;
  return (1 - f) * Q[i] + f * Q[(i + 1) % n];
}

void check_loop(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop) {
  if (loop.size() < 3)
    throw std::invalid_argument("the outer loop has " + std::to_string(loop.size()) +
                                " points; a boundary map needs at least 3");
  for (int i : loop)
    if (i < 0 || static_cast<std::size_t>(i) >= P.size())
      throw std::invalid_argument("the outer loop has point index " + std::to_string(i) +
                                  " outside the cloud of " + std::to_string(P.size()) + " points");
}

}  // namespace

std::vector<Eigen::Vector3d> smoothed_loop(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop,
                                           int half_window) {
  check_loop(P, loop);
  const int n = static_cast<int>(loop.size());
  const int w = std::clamp(half_window, 0, (n - 1) / 2);
  std::vector<Eigen::Vector3d> Q(n);
  if (w == 0) {
    for (int i = 0; i < n; ++i) Q[i] = P[loop[i]];
    return Q;
  }
  // Running sum over the closed loop.
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int j = -w; j <= w; ++j) sum += P[loop[(j + n) % n]];
  for (int i = 0; i < n; ++i) {
    Q[i] = sum / (2 * w + 1);
    sum += P[loop[(i + w + 1) % n]] - P[loop[(i - w + n) % n]];
  }
  return Q;
}

std::vector<std::pair<int, Eigen::Vector2d>> outer_band_values(const std::vector<Eigen::Vector3d>& P,
                                                               const std::vector<Eigen::Vector3d>& N,
                                                               const std::vector<std::uint8_t>& is_boundary,
                                                               const std::vector<std::vector<int>>& loops,
                                                               const UVMap& map) {
  const auto& outer = map.outer_loop;
  check_loop(P, outer);
  if (is_boundary.size() != P.size())
    throw std::invalid_argument("the boundary flags are for " + std::to_string(is_boundary.size()) +
                                " points but the cloud has " + std::to_string(P.size()));
  if (!N.empty() && N.size() != P.size())
    throw std::invalid_argument("the cloud has " + std::to_string(N.size()) + " normals for " +
                                std::to_string(P.size()) + " points");
  if (map.boundary_uv.size() != outer.size())
    throw std::invalid_argument("the boundary map has " + std::to_string(outer.size()) + " loop points and " +
                                std::to_string(map.boundary_uv.size()) + " boundary positions");
  const int n = static_cast<int>(outer.size());
  // 1: on the outer loop; 2: on a hole loop.
  std::vector<char> loop_of(P.size(), 0);
  std::vector<Eigen::Vector3d> holes;
  for (std::size_t l = 1; l < loops.size(); ++l)
    for (int i : loops[l])
      if (i >= 0 && static_cast<std::size_t>(i) < P.size()) loop_of[i] = 2, holes.push_back(P[i]);
  for (int i : outer) loop_of[i] = 1;
  Eigen::Vector3d plane_c, plane_n;
  if (N.empty()) best_fit_plane(P, N, plane_c, plane_n);

  const std::vector<Eigen::Vector3d> Q = smoothed_loop(P, outer);
  // Local sampling step: the raw loop's segment lengths averaged like the positions.
  std::vector<double> step(n);
  {
    const int w = std::clamp(kLoopSmoothing, 0, (n - 1) / 2);
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int j = -w; j <= w; ++j) {
        int a = ((i + j) % n + n) % n;
        s += (P[outer[(a + 1) % n]] - P[outer[a]]).norm();
      }
      step[i] = s / (2 * w + 1);
    }
  }
  KnnIndex on_outer(Q);
  std::unique_ptr<KnnIndex> on_holes = holes.empty() ? nullptr : std::make_unique<KnnIndex>(holes);
  std::vector<std::pair<int, Eigen::Vector2d>> out;
  std::vector<int> idx;
  std::vector<double> sq;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (loop_of[i] != 1 && (!is_boundary[i] || loop_of[i] == 2)) continue;
    // Nearest point on the smoothed loop: the segments next to the few nearest vertices.
    on_outer.query(P[i], std::min(4, n), idx, sq);
    double best = std::numeric_limits<double>::infinity(), best_t = 0;
    int best_seg = -1;
    for (int v : idx)
      for (int seg : {(v + n - 1) % n, v}) {
        const Eigen::Vector3d& a = Q[seg];
        Eigen::Vector3d ab = Q[(seg + 1) % n] - a;
        double len2 = ab.squaredNorm();
        double t = len2 > 0 ? std::clamp((P[i] - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
        double d = (P[i] - (a + t * ab)).norm();
        if (d < best) best = d, best_t = t, best_seg = seg;
      }
    if (best_seg < 0) continue;
    if (loop_of[i] != 1) {
      if (best > kBandWidth * step[best_seg]) continue;  // a false boundary point inside the patch
      if (on_holes) {
        on_holes->query(P[i], 1, idx, sq);
        if (!idx.empty() && std::sqrt(sq[0]) < best) continue;  // a hole's band: stays free
      }
    }
    const Eigen::Vector3d& qa = Q[best_seg];
    const Eigen::Vector3d& qb = Q[(best_seg + 1) % n];
    const Eigen::Vector2d& ua = map.boundary_uv[best_seg];
    const Eigen::Vector2d& ub = map.boundary_uv[(best_seg + 1) % n];
    Eigen::Vector2d uv = (1 - best_t) * ua + best_t * ub;
    // Inward offset: the loop runs with the patch on its left seen from the normal, and so does
    // the domain boundary in (u,v); a point d inside the smoothed loop goes d inside the domain.
    Eigen::Vector3d T = (qb - qa).normalized();
    Eigen::Vector3d inward = (N.empty() ? plane_n : N[i]).cross(T);
    Eigen::Vector2d duv = ub - ua;
    if (inward.norm() > 1e-6 && duv.norm() > 0 && T.allFinite()) {
      double d = std::max(0.0, (P[i] - ((1 - best_t) * qa + best_t * qb)).dot(inward.normalized()));
      uv += d * Eigen::Vector2d(-duv.y(), duv.x()).normalized();
    }
    out.emplace_back(static_cast<int>(i), uv);
  }
  return out;
}

std::vector<int> parse_corners(const std::string& text, std::size_t loop_size) {
  std::vector<int> c;
  if (text.find_first_not_of(" \t") == std::string::npos) return c;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    long long v = 0;
    try {
      v = std::stoll(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos)
      throw std::invalid_argument("corners must be 4 comma-separated integers \"i,j,k,l\", got \"" + text + "\"");
    if (v < 0 || static_cast<std::size_t>(v) >= loop_size)
      throw std::invalid_argument("corner " + std::to_string(v) + " is outside the outer loop's positions 0.." +
                                  std::to_string(loop_size - 1));
    c.push_back(static_cast<int>(v));
  }
  if (c.size() != 4)
    throw std::invalid_argument("corners must be 4 comma-separated integers \"i,j,k,l\", got \"" + text + "\"");
  std::vector<int> s(c);
  std::sort(s.begin(), s.end());
  if (std::adjacent_find(s.begin(), s.end()) != s.end())
    throw std::invalid_argument("corners must be 4 distinct positions, got \"" + text + "\"");
  return c;
}

std::vector<int> detect_corners(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& loop) {
  check_loop(P, loop);
  const std::size_t n = loop.size();
  if (n < 4) throw std::invalid_argument("a rectangle map needs an outer loop of at least 4 points");
  const std::vector<Eigen::Vector3d> Q = smoothed_loop(P, loop);
  std::vector<double> cum = cumulative_lengths(Q);
  const double L = cum[n];
  if (!(L > 0)) throw std::invalid_argument("the outer loop has zero length");
  const double h = L / 48, sep = L / 16;
  std::vector<double> turn(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d a = Q[i] - point_at(Q, cum, cum[i] - h);
    Eigen::Vector3d b = point_at(Q, cum, cum[i] + h) - Q[i];
    double na = a.norm(), nb = b.norm();
    turn[i] = (na > 0 && nb > 0) ? std::acos(std::clamp(a.dot(b) / (na * nb), -1.0, 1.0)) : 0.0;
  }
  std::vector<int> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return turn[a] > turn[b]; });
  auto arc_gap = [&](int a, int b) {
    double d = std::abs(cum[a] - cum[b]);
    return std::min(d, L - d);
  };
  std::vector<int> corners;
  for (int i : order) {
    if (corners.size() == 4) break;
    bool far = std::all_of(corners.begin(), corners.end(), [&](int c) { return arc_gap(i, c) >= sep; });
    if (far) corners.push_back(i);
  }
  const double min_turn = std::numbers::pi / 6;
  if (corners.size() < 4 || turn[corners[3]] < min_turn) {
    // No 4 real corners: split the loop in quarters from its sharpest point.
    int c0 = order[0];
    corners = {c0};
    for (int q = 1; q < 4; ++q) {
      double s = std::fmod(cum[c0] + q * L / 4, L);
      auto off = [&](std::size_t i) {
        double d = std::abs(cum[i] - s);
        return std::min(d, L - d);
      };
      std::size_t best = 0;
      for (std::size_t i = 1; i < n; ++i)
        if (off(i) < off(best)) best = i;
      corners.push_back(static_cast<int>(best));
    }
  }
  std::sort(corners.begin(), corners.end());
  return corners;
}

UVMap map_boundary(const std::vector<Eigen::Vector3d>& P, const std::vector<int>& outer,
                   BoundaryDomain domain, std::vector<int> corners) {
  check_loop(P, outer);
  const std::size_t n = outer.size();
  std::vector<double> cum = cumulative_lengths(smoothed_loop(P, outer));
  const double L = cum[n];
  if (!(L > 0)) throw std::invalid_argument("the outer loop has zero length");
  UVMap m;
  m.outer_loop = outer;
  m.boundary_uv.resize(n);
  if (domain == BoundaryDomain::Disk) {
    m.domain = "disk";
    m.radius = L / (2 * std::numbers::pi);
    for (std::size_t i = 0; i < n; ++i) {
      double th = 2 * std::numbers::pi * cum[i] / L;
      m.boundary_uv[i] = m.radius * Eigen::Vector2d(std::cos(th), std::sin(th));
    }
    return m;
  }

  m.domain = "rectangle";
  if (corners.empty()) corners = detect_corners(P, outer);
  if (corners.size() != 4) throw std::invalid_argument("a rectangle map needs exactly 4 corners");
  for (int c : corners)
    if (c < 0 || static_cast<std::size_t>(c) >= n)
      throw std::invalid_argument("corner " + std::to_string(c) + " is outside the outer loop's positions");
  std::sort(corners.begin(), corners.end());
  if (std::adjacent_find(corners.begin(), corners.end()) != corners.end())
    throw std::invalid_argument("the 4 corners must be distinct positions of the outer loop");
  // Chord length of side k (corner k to corner k+1, the last one wrapping around).
  double side[4];
  for (int k = 0; k < 4; ++k) {
    double a = cum[corners[k]], b = k < 3 ? cum[corners[k + 1]] : L + cum[corners[0]];
    side[k] = b - a;
    if (!(side[k] > 0))
      throw std::invalid_argument("side " + std::to_string(k + 1) + " of the rectangle has zero length");
  }
  m.width = (side[0] + side[2]) / 2;
  m.height = (side[1] + side[3]) / 2;
  const double W = m.width, H = m.height;
  const Eigen::Vector2d corner_uv[5] = {{0, 0}, {W, 0}, {W, H}, {0, H}, {0, 0}};
  for (int k = 0; k < 4; ++k) {
    std::size_t i = static_cast<std::size_t>(corners[k]);
    const std::size_t end = static_cast<std::size_t>(corners[(k + 1) % 4]);
    do {
      double s = cum[i] - cum[corners[k]];
      if (s < 0) s += L;  // the last side wraps past outer[0]
      double lambda = s / side[k];
      m.boundary_uv[i] = (1 - lambda) * corner_uv[k] + lambda * corner_uv[k + 1];
      i = (i + 1) % n;
    } while (i != end);
  }
  m.corners = corners;
  return m;
}

}  // namespace scallop
