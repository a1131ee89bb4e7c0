#include "nodes/param/check.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "nodes/geom/angular_gap.h"
#include "nodes/geom/tangent_frame.h"

namespace scallop {

MapCheck check_map(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                   const Neighborhoods& nbrs, const std::vector<Eigen::Vector2d>& uv) {
  const std::size_t n = P.size();
  if (N.size() != n)
    throw std::invalid_argument("the map check needs normals (the cloud has " + std::to_string(N.size()) +
                                " normals for " + std::to_string(n) + " points)");
  if (uv.size() != n)
    throw std::invalid_argument("the map has " + std::to_string(uv.size()) + " (u,v) positions for " +
                                std::to_string(n) + " points");
  if (nbrs.size() != n || nbrs.k < 2)
    throw std::invalid_argument("the neighbourhoods do not match the cloud (" + std::to_string(nbrs.size()) +
                                " points, k = " + std::to_string(nbrs.k) + ")");
  for (int idx : nbrs.indices)
    if (idx < 0 || static_cast<std::size_t>(idx) >= n)
      throw std::invalid_argument("a neighbour index is out of range");

  MapCheck c;
  c.distortion.assign(n, 0.0);
  c.folded.assign(n, 0);
  std::vector<int> flipped_triangles(n, 0);
  const int k = nbrs.k;
  const double cos_lo = std::cos(10 * std::numbers::pi / 180), cos_hi = std::cos(170 * std::numbers::pi / 180);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    // Each neighbour's offset in the tangent plane (X) and in (u,v) (Y), by columns; fixed-size
    // 2 x 2 sums below (Eigen's general products of 2 x k blocks took three quarters of the node).
    std::vector<Eigen::Vector2d> X(k), Y(k);
    std::vector<std::pair<double, int>> ang(k);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      Eigen::Vector3d t1, t2;
      tangent_frame(N[i], t1, t2);
      Eigen::Matrix2d XXt = Eigen::Matrix2d::Zero(), YXt = Eigen::Matrix2d::Zero();
      for (int j = 0; j < k; ++j) {
        int q = nbrs.index(i, j);
        Eigen::Vector3d d = P[q] - P[i];
        X[j] = {d.dot(t1), d.dot(t2)};
        Y[j] = uv[q] - uv[i];
        XXt += X[j] * X[j].transpose();
        YXt += Y[j] * X[j].transpose();
        ang[j] = {pseudo_angle(X[j].x(), X[j].y()), j};
      }
      // Angle distortion from the least-squares Jacobian J = Y X^T (X X^T)^-1.
      double ratio = std::numeric_limits<double>::infinity();
      double det = 0;
      if (XXt.determinant() > 1e-12 * XXt.trace() * XXt.trace()) {
        Eigen::Matrix2d J = YXt * XXt.inverse();
        det = J.determinant();
        Eigen::JacobiSVD<Eigen::Matrix2d> svd(J);
        double s1 = svd.singularValues()(0), s2 = svd.singularValues()(1);
        if (s2 > 0) ratio = s1 / s2;
      }
      c.distortion[i] = ratio;
      // Fold-overs: orientation of the fan triangles between angularly consecutive neighbours
      // whose directions are 10 to 170 degrees apart (cross >= 0 and the cosine between them).
      std::sort(ang.begin(), ang.end());
      int tri = 0, flipped = 0;
      for (int j = 0; j < k; ++j) {
        const int a = ang[j].second, b = ang[(j + 1) % k].second;
        const double cross = X[a].x() * X[b].y() - X[a].y() * X[b].x(), dot = X[a].dot(X[b]);
        const double lengths = X[a].norm() * X[b].norm();
        if (a == b || !(lengths > 0) || cross < 0 || dot > cos_lo * lengths || dot < cos_hi * lengths) continue;
        ++tri;
        if (Y[a].x() * Y[b].y() - Y[a].y() * Y[b].x() < 0) ++flipped;
      }
      c.folded[i] = (det < 0 || 2 * flipped > tri) ? 1 : 0;
      flipped_triangles[i] = flipped;
    }
  });

  for (std::size_t i = 0; i < n; ++i)
    if (c.folded[i]) {
      if (c.first_foldover < 0) c.first_foldover = static_cast<int>(i);
      ++c.foldovers;
    }

  // Statistics of the distortion.
  std::vector<double> s(c.distortion);
  std::sort(s.begin(), s.end());
  auto pct = [&](double p) { return s.empty() ? 0.0 : s[std::min(s.size() - 1, static_cast<std::size_t>(p * (s.size() - 1) + 0.5))]; };
  double sum = 0;
  std::size_t finite = 0;
  for (double v : s)
    if (std::isfinite(v)) sum += v, ++finite;
  const std::vector<double> edges = {1, 1.1, 1.25, 1.5, 2, 3, 5, 10};
  std::vector<std::size_t> counts(edges.size(), 0);  // last bin: >= 10 (and infinite)
  for (double v : s) {
    std::size_t b = static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), v) - edges.begin());
    counts[b == 0 ? 0 : b - 1]++;
  }
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json("inf"); };
  nlohmann::json conf = {
      {"measure", "sigma1/sigma2 of the local least-squares Jacobian (1 = conformal)"},
      {"mean", finite ? sum / static_cast<double>(finite) : 0.0},
      {"p50", num(pct(0.5))},
      {"p95", num(pct(0.95))},
      {"max", num(s.empty() ? 0.0 : s.back())},
      {"degenerate_points", s.size() - finite},
      {"histogram", {{"edges", edges}, {"counts", counts}}}};
  std::size_t flipped_total = 0, points_with_flips = 0;
  for (int f : flipped_triangles) flipped_total += f, points_with_flips += f > 0;
  c.report = {{"points", n},
              {"conformality", conf},
              {"foldovers", c.foldovers},
              {"first_foldover", nullptr},
              {"flipped_fan_triangles", flipped_total},
              {"points_with_a_flipped_fan_triangle", points_with_flips}};
  if (c.first_foldover >= 0) {
    const auto& p = P[c.first_foldover];
    c.report["first_foldover"] = {{"index", c.first_foldover}, {"position", {p.x(), p.y(), p.z()}}};
  }
  return c;
}

std::string foldover_message(const MapCheck& check, const std::vector<Eigen::Vector3d>& P) {
  char where[128] = "";
  if (check.first_foldover >= 0) {
    const auto& p = P[check.first_foldover];
    std::snprintf(where, sizeof where, "%.3f, %.3f, %.3f", p.x(), p.y(), p.z());
  }
  return "the (u,v) map folds over at " + std::to_string(check.foldovers) + " points (first near " + where +
         "): tool paths there would cross. graphs/raster-zigzag.json maps the patch by its own xy, which "
         "cannot fold (the bunny range scan at max_slope 75: 10 fold-overs here, none there, the 2 points "
         "where it overhangs reported); with this graph no option is known to remove every fold-over: "
         "param.laplacian's heat scheme left the fewest on the head scans measured (99 -> 3 and 113 -> 81 "
         "fold-overs); "
         "allow_foldovers plans anyway and the certificate says whether the paths hold (slow: over 15 min "
         "on a 32 000-point face mask)";
}

}  // namespace scallop
