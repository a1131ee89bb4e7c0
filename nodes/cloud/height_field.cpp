#include "nodes/cloud/height_field.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nanoflann.hpp>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

#include "nodes/cloud/knn.h"
#include "nodes/geom/kd_tree.h"
#include "nodes/geom/point_text.h"

namespace scallop {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// nanoflann over the xy coordinates of the points, read in place.
using XyAdaptor = PointsAdaptor<Eigen::Vector3d>;
using XyTree = KdTree<Eigen::Vector3d, 2>;

// Visits every point within the search radius (in xy) of point i and keeps, among those that
// are above i and on another layer, the clearest one (largest separation).
class LayerProbe {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  LayerProbe(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
             const KnnIndex& index3d, const std::vector<char>& skip, std::size_t i,
             double sq_radius, double min_sep)
      : P_(P),
        N_(N),
        index3d_(index3d),
        skip_(skip),
        i_(i),
        sq_radius_(sq_radius),
        min_sep_(min_sep) {}

  std::size_t size() const { return 0; }
  bool full() const { return true; }
  double worstDist() const { return sq_radius_; }

  bool addPoint(double sq_dist, IndexType j) {
    if (sq_dist > sq_radius_ || j == i_ || skip_[j]) return true;
    const Eigen::Vector3d d = P_[j] - P_[i_];
    if (d.z() <= 0) return true;  // only points above i matter; the pair is seen from below
    // Distance of each point from the other's tangent plane: both small on one smooth sheet
    // (a vertical wall included), both large between stacked sheets.
    const double sep = std::min(std::abs(N_[i_].dot(d)), std::abs(N_[j].dot(d)));
    if (sep > min_sep_ && sep > best_sep && gap_between(j)) {
      best_sep = sep;
      best_dz = d.z();
    }
    return true;
  }

  double best_sep = 0, best_dz = 0;

 private:
  // Is the space between p_i and p_j empty? Stacked sheets have a gap between them; a vertical
  // wall (whose bottom and top corners have blurred normals) or a floor point next to the top
  // edge of a wall does not: the wall runs between them.
  bool gap_between(std::uint32_t j) const {
    const Eigen::Vector3d mid = 0.5 * (P_[i_] + P_[j]);
    return (P_[index3d_.nearest(mid)] - mid).squaredNorm() > sq_radius_;
  }

  const std::vector<Eigen::Vector3d>& P_;
  const std::vector<Eigen::Vector3d>& N_;
  const KnnIndex& index3d_;
  const std::vector<char>& skip_;
  std::size_t i_;
  double sq_radius_, min_sep_;
};

int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];  // path halving
    x = parent[x];
  }
  return x;
}

std::string percent(double fraction) {
  char buf[32];
  const double p = 100.0 * fraction;
  std::snprintf(buf, sizeof buf, p >= 10 || p == 0 ? "%.0f %%" : "%.1f %%", p);
  return buf;
}

std::string number_text(double x, const char* format = "%.1f") {
  char buf[32];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

}  // namespace

std::vector<int> knn_components(const Neighborhoods& nbrs, std::vector<std::size_t>& sizes) {
  const std::size_t n = nbrs.size();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  // Union-find over the directed lists is the symmetric graph's components.
  for (std::size_t i = 0; i < n; ++i)
    for (int j = 0; j < nbrs.k; ++j) {
      const int a = find_root(parent, static_cast<int>(i));
      const int b = find_root(parent, nbrs.index(i, j));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // root = smallest index
    }
  std::vector<std::size_t> root_size(n, 0);
  std::vector<int> root(n);
  for (std::size_t i = 0; i < n; ++i) ++root_size[root[i] = find_root(parent, static_cast<int>(i))];
  std::vector<int> roots;
  for (std::size_t i = 0; i < n; ++i)
    if (root_size[i] > 0) roots.push_back(static_cast<int>(i));
  // Roots are the smallest index of their component, so this orders ties by first point.
  std::stable_sort(roots.begin(), roots.end(),
                   [&](int a, int b) { return root_size[a] > root_size[b]; });
  std::vector<int> label_of_root(n, -1);
  sizes.assign(roots.size(), 0);
  for (std::size_t c = 0; c < roots.size(); ++c) {
    label_of_root[roots[c]] = static_cast<int>(c);
    sizes[c] = root_size[roots[c]];
  }
  std::vector<int> label(n);
  for (std::size_t i = 0; i < n; ++i) label[i] = label_of_root[root[i]];
  return label;
}

HeightFieldStats analyze_height_field(const std::vector<Eigen::Vector3d>& P,
                                      const std::vector<Eigen::Vector3d>& N,
                                      const Neighborhoods& nbrs, const HeightFieldLimits& limits) {
  const std::size_t n = P.size();
  if (n == 0) throw std::invalid_argument("the cloud is empty");
  if (N.size() != n)
    throw std::invalid_argument(N.empty() ? "the cloud has no normals; compute them first "
                                            "(cloud.normals)"
                                          : "the cloud has " + std::to_string(N.size()) +
                                                " normals for " + std::to_string(n) + " points");
  if (nbrs.k < 1 || nbrs.size() != n || nbrs.sq_dists.size() != nbrs.indices.size())
    throw std::invalid_argument("the neighbours are for " + std::to_string(nbrs.size()) +
                                " points, the cloud has " + std::to_string(n) +
                                "; compute them from this cloud");
  for (std::size_t i = 0; i < n; ++i) {
    if (!P[i].allFinite() || !N[i].allFinite())
      throw std::invalid_argument("point " + std::to_string(i) +
                                  " has a NaN or infinite coordinate or normal");
  }
  for (int idx : nbrs.indices)
    if (idx < 0 || static_cast<std::size_t>(idx) >= n)
      throw std::invalid_argument("the neighbours refer to point " + std::to_string(idx) +
                                  ", the cloud has " + std::to_string(n) + " points");

  HeightFieldStats s;
  s.points = n;
  s.k = nbrs.k;

  s.spacing = median_spacing(nbrs);  // exact duplicates skipped

  s.extents = principal_extents(P);
  s.component = knn_components(nbrs, s.component_sizes);
  const double speck_limit = limits.min_component_fraction * static_cast<double>(n);
  std::vector<char> speck(n, 0);
  for (std::size_t c = 0; c < s.component_sizes.size(); ++c) {
    if (static_cast<double>(s.component_sizes[c]) >= speck_limit)
      ++s.significant_components;
    else
      s.speck_points += s.component_sizes[c];
  }
  for (std::size_t i = 0; i < n; ++i)
    speck[i] = static_cast<double>(s.component_sizes[s.component[i]]) < speck_limit;
  s.component_centroids.assign(std::min<std::size_t>(s.component_sizes.size(), 10),
                               Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i)
    if (static_cast<std::size_t>(s.component[i]) < s.component_centroids.size())
      s.component_centroids[s.component[i]] += P[i];
  for (std::size_t c = 0; c < s.component_centroids.size(); ++c)
    s.component_centroids[c] /= static_cast<double>(s.component_sizes[c]);

  // Extent and slopes of the points that count.
  const double cos_max = std::cos(limits.max_slope_deg * kDeg);
  double min_nz = 2;
  bool first = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (speck[i]) continue;
    const Eigen::Vector3d& p = P[i];
    if (first) {
      s.xy_min = s.xy_max = p.head<2>();
      s.z_min = s.z_max = p.z();
      first = false;
    }
    s.xy_min = s.xy_min.cwiseMin(p.head<2>());
    s.xy_max = s.xy_max.cwiseMax(p.head<2>());
    s.z_min = std::min(s.z_min, p.z());
    s.z_max = std::max(s.z_max, p.z());
    const double nz = std::abs(N[i].z()) / std::max(N[i].norm(), 1e-300);
    if (nz < cos_max) ++s.steep_points;
    if (nz < min_nz) {
      min_nz = nz;
      s.steepest = p;
    }
  }
  if (min_nz <= 1) s.max_slope_deg = std::acos(std::min(1.0, min_nz)) / kDeg;

  // Layers: every point looks for points above it within 2h in xy.
  s.under.assign(n, 0);
  if (s.spacing > 0 && s.significant_components > 0) {
    XyAdaptor adaptor{P};
    XyTree tree(2, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    const KnnIndex index3d(P);
    const double radius = 2 * s.spacing;
    const double min_sep = limits.layer_gap * s.spacing;
    std::vector<double> sep(n, 0), dz(n, 0);
    const auto& order = tree.vAcc;  // queries in leaf order stay in cache
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t q = r.begin(); q != r.end(); ++q) {
                          const std::size_t i = order[q];
                          if (speck[i]) continue;
                          LayerProbe probe(P, N, index3d, speck, i, radius * radius, min_sep);
                          tree.findNeighbors(probe, P[i].data(), nanoflann::SearchParams());
                          sep[i] = probe.best_sep;
                          dz[i] = probe.best_dz;
                        }
                      });
    double best = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (sep[i] <= 0) continue;
      s.under[i] = 1;
      ++s.layered_points;
      if (sep[i] > best) {
        best = sep[i];
        s.layered_example = P[i];
        s.layered_example_gap = dz[i];
      }
    }
  }
  return s;
}

std::string height_field_problem(const HeightFieldStats& s, const HeightFieldLimits& limits) {
  const double n = static_cast<double>(s.points);
  if (s.points < static_cast<std::size_t>(std::max(limits.min_points, 0)))
    return "the cloud has " + std::to_string(s.points) + " points; at least " +
           std::to_string(limits.min_points) + " are needed to describe a patch to machine";
  // First: a line gets normals of any tilt around it, so every later check would mislead.
  if (auto line = one_dimensional_problem(s.extents, s.spacing); !line.empty()) return line;
  const std::string graph = std::to_string(s.k) + "-nearest-neighbour graph";
  if (s.significant_components == 0)
    return "the cloud falls apart into " + std::to_string(s.component_sizes.size()) +
           " small pieces in the " + graph + ", none with " +
           percent(limits.min_component_fraction) +
           " of the points: it is too sparse or noisy to be one patch; clean it or use more "
           "neighbours";
  if (s.significant_components > limits.max_components) {
    std::string parts;
    const int shown = std::min(s.significant_components, 6);
    for (int c = 0; c < shown; ++c)
      parts += (c ? ", " : "") + percent(static_cast<double>(s.component_sizes[c]) / n);
    if (shown < s.significant_components) parts += ", ...";
    std::string specks;
    if (s.speck_points > 0) {
      const std::size_t count = s.component_sizes.size() - s.significant_components;
      specks = "; " + std::to_string(count) + (count == 1 ? " speck" : " specks") + " with " +
               percent(static_cast<double>(s.speck_points) / n) + " ignored";
    }
    // Where the second part is tells the user which one to remove.
    std::string where;
    if (s.component_centroids.size() > 1)
      where = "; the second centred near " + point_text(s.component_centroids[1], 1);
    const std::string plan =
        limits.max_components == 1
            ? "scallop plans one patch at a time"
            : "at most " + std::to_string(limits.max_components) + " are allowed (max_components)";
    return "the cloud has " + std::to_string(s.significant_components) + " separate parts (" +
           parts + " of the points, not linked in the " + graph + specks + where + "): " + plan +
           "; split it or remove the others";
  }
  if (static_cast<double>(s.layered_points) > limits.max_layered_fraction * n)
    return "not a height field seen from +Z: " + std::to_string(s.layered_points) + " points (" +
           percent(static_cast<double>(s.layered_points) / n) +
           ") lie under other points of the cloud (a closed object, an overhang or several "
           "layers), e.g. near " +
           point_text(s.layered_example, 1) + " with a layer " + number_text(s.layered_example_gap) +
           " mm above it; a 3-axis machine cannot reach them (a scan's stray points off the surface look "
           "the same: --set clean.remove_stray=true drops them)";
  if (static_cast<double>(s.steep_points) > limits.max_steep_fraction * n)
    return "walls steeper than " + number_text(limits.max_slope_deg, "%g") +
           "°: " + std::to_string(s.steep_points) + " points (" +
           percent(static_cast<double>(s.steep_points) / n) + ", more than the " +
           percent(limits.max_steep_fraction) + " allowed), up to " + number_text(s.max_slope_deg) +
           "° near " + point_text(s.steepest, 1) +
           "; a ball-end cutter coming from +Z cannot finish them; turn the part to face +Z "
           "or raise max_slope";
  return {};
}

nlohmann::json to_json(const HeightFieldStats& s, const HeightFieldLimits& limits) {
  const double n = static_cast<double>(std::max<std::size_t>(s.points, 1));
  nlohmann::json parts = nlohmann::json::array();
  for (std::size_t c = 0; c < s.component_sizes.size() && c < 10; ++c)
    parts.push_back(s.component_sizes[c]);
  return {
      {"points", s.points},
      {"spacing_mm", s.spacing},
      {"extents_mm", {s.extents.length, s.extents.width, s.extents.thickness}},
      {"neighbours", s.k},
      {"components",
       {{"count", s.component_sizes.size()},
        {"significant", s.significant_components},
        {"largest_sizes", parts},
        {"speck_points", s.speck_points}}},
      {"layered",
       {{"points", s.layered_points},
        {"fraction", static_cast<double>(s.layered_points) / n},
        {"min_gap_mm", limits.layer_gap * s.spacing},
        {"example", s.layered_points ? nlohmann::json{s.layered_example.x(), s.layered_example.y(),
                                                      s.layered_example.z()}
                                     : nlohmann::json()}}},
      {"slope",
       {{"max_deg", s.max_slope_deg},
        {"steepest", {s.steepest.x(), s.steepest.y(), s.steepest.z()}},
        {"limit_deg", limits.max_slope_deg},
        {"steep_points", s.steep_points},
        {"steep_fraction", static_cast<double>(s.steep_points) / n}}},
      {"xy_bbox", {{"min", {s.xy_min.x(), s.xy_min.y()}}, {"max", {s.xy_max.x(), s.xy_max.y()}}}},
      {"z_range", {s.z_min, s.z_max}},
  };
}

}  // namespace scallop
