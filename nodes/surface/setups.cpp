#include "nodes/surface/setups.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/surface/fit_bspline.h"

namespace scallop {
namespace {

constexpr int kSamples = 17;  // normals per side of a patch's (u, v) square
constexpr int kSphere = 2000;  // candidate axes spread over the sphere
constexpr double kSquareBonus = 0.005;  // a square axis wins a tie within this much n . a (5.7 degrees off a flat face)

std::string axis_name(const Eigen::Vector3d& a) {
  static const char* names[] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (std::abs(std::abs(a[k]) - 1) < 1e-9) return std::string(a[k] > 0 ? "+" : "-") + names[k];
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.3f, %.3f, %.3f)", a.x(), a.y(), a.z());
  return buf;
}

double smallest_dot(const std::vector<Eigen::Vector3d>& normals, const Eigen::Vector3d& a) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& n : normals) m = std::min(m, n.dot(a));
  return m;
}

nlohmann::json hidden_patches_report(const std::vector<HiddenPatch>& hidden) {
  nlohmann::json list = nlohmann::json::array();
  for (const HiddenPatch& h : hidden)
    list.push_back({{"patch", h.patch}, {"samples", h.samples}, {"at", {h.at.x(), h.at.y(), h.at.z()}}});
  return list;
}

}  // namespace

std::vector<Eigen::Vector3d> sphere_lattice(int n) {
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < n; ++k) {
    const double z = 1 - (2 * k + 1.0) / n, rho = std::sqrt(1 - z * z), phi = k * M_PI * (3 - std::sqrt(5.0));
    out.emplace_back(rho * std::cos(phi), rho * std::sin(phi), z);
  }
  return out;
}

Eigen::Matrix3d rotation_to_z(const Eigen::Vector3d& a) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  if (a.dot(z) < -1 + 1e-12) return Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return Eigen::Quaterniond::FromTwoVectors(a, z).toRotationMatrix();
}

void place_setup(Setup& setup, const std::vector<Eigen::Vector3d>& part) {
  setup.rotation = rotation_to_z(setup.axis);
  setup.translation.setZero();
  if (part.empty()) return;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : part) {
    const Eigen::Vector3d q = setup.rotation * p;
    lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  setup.translation = Eigen::Vector3d(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
}

std::vector<Setup> plan_setups(const Surfaces& surfaces, const Mesh& part, const SetupOptions& o) {
  const std::vector<Eigen::Vector3d>& points = part.vertices;
  const std::size_t np = surfaces.patches.size();
  if (np == 0) throw std::invalid_argument("there are no patches to set up");
  if (!(o.min_normal_dot > 0 && o.min_normal_dot <= 1))
    throw std::invalid_argument("min_normal_dot must lie in (0, 1]");

  // Each patch's sampled points and normals.
  std::vector<std::vector<Eigen::Vector3d>> normals(np), positions(np);
  std::vector<Eigen::Vector3d> candidates;
  for (std::size_t p = 0; p < np; ++p) {
    const SurfacePatch& sp = surfaces.patches[p];
    if (!(sp.direction.allFinite() && std::abs(sp.direction.norm() - 1) < 1e-6))
      throw std::invalid_argument("patch " + std::to_string(p) + ": its direction is not a unit vector");
    const BSplinePatch patch = machining_surface(sp);  // throws on a malformed surface
    for (int i = 0; i < kSamples; ++i)
      for (int j = 0; j < kSamples; ++j) {
        const SurfaceSample x = patch({double(j) / (kSamples - 1), double(i) / (kSamples - 1)});
        normals[p].push_back(x.normal);
        positions[p].push_back(x.position);
      }
    candidates.push_back(sp.direction);
  }
  if (surfaces.base_direction.norm() > 0.5) candidates.push_back(-surfaces.base_direction.normalized());
  for (int k = 0; k < 3; ++k) candidates.push_back(Eigen::Vector3d::Unit(k)), candidates.push_back(-Eigen::Vector3d::Unit(k));
  const std::size_t first_sphere = candidates.size();
  const std::vector<Eigen::Vector3d> sphere = sphere_lattice(kSphere);
  if (o.any_axis) candidates.insert(candidates.end(), sphere.begin(), sphere.end());

  // low[c][p]: candidate c's smallest n . a over patch p. threshold[p]: the least a setup other than
  // the patch's own may have there: min_normal_dot, or half the patch's best when that is lower.
  std::vector<std::vector<double>> low;
  const auto add_low_row = [&](const Eigen::Vector3d& a) {
    low.emplace_back(np);
    for (std::size_t p = 0; p < np; ++p) low.back()[p] = smallest_dot(normals[p], a);
  };
  for (const auto& a : candidates) add_low_row(a);
  std::vector<double> threshold(np);
  for (std::size_t p = 0; p < np; ++p) {
    double best = -2;
    for (const auto& row : low) best = std::max(best, row[p]);
    threshold[p] = std::min(o.min_normal_dot, std::max(0.5 * best, 1e-3));
  }
  // own[p]: the candidate that may cut patch p whatever the part hides: its own direction, or the
  // one found below that the part hides less of it from.
  std::vector<std::size_t> own(np);
  std::iota(own.begin(), own.end(), std::size_t(0));

  // Reach: from every sample, a little off the surface, the ray along the axis must leave the part
  // without meeting it (an overhang hides the patch from that axis; the ball's width is the gouge
  // guard's matter). hidden[c][p] counts the samples it does not, where c may cut p at all.
  std::vector<std::vector<std::size_t>> hidden(candidates.size(), std::vector<std::size_t>(np, 0));
  std::vector<std::vector<Eigen::Vector3d>> hidden_sum(candidates.size(), std::vector<Eigen::Vector3d>(np, Eigen::Vector3d::Zero()));
  if (part.num_faces() > 0) {
    Eigen::Vector3d lo = points[0], hi = points[0];
    for (const auto& q : points) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    // Started 0.01 of the part's diagonal along the axis: the fitted surface lies up to a few
    // tenths of that off the mesh (docs/surfaces.md), and a ray starting inside the part would
    // call every patch hidden (measured on the fandisk at 0.002: all 289 samples of 7 patches).
    const double offset = 1e-2 * (hi - lo).norm();
    const MeshDistance mesh(part);
    // Hidden samples of patch p along a, counted up to limit; their positions summed into sum.
    const auto count_hidden = [&](const Eigen::Vector3d& a, std::size_t p, std::size_t limit, Eigen::Vector3d* sum) {
      std::size_t n = 0;
      for (std::size_t k = 0; k < positions[p].size() && n < limit; ++k)
        if (std::isfinite(mesh.ray_distance(positions[p][k] + offset * a, a))) {
          ++n;
          if (sum) *sum += positions[p][k];
        }
      return n;
    };
    const auto measure_from = [&](std::size_t first) {
      const std::size_t count = (candidates.size() - first) * np;
      tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        const std::size_t c = first + i / np, p = i % np;
        if (c == own[p] || low[c][p] >= threshold[p]) hidden[c][p] = count_hidden(candidates[c], p, positions[p].size(), &hidden_sum[c][p]);
      });
    };
    measure_from(0);
    // A patch the part hides from its own direction (a bore's wall: the opposite wall is in the
    // way) is given the direction of the sphere's lattice that reaches the most of its samples
    // (ties to the larger smallest n . a, at least its threshold), when that is more than its own
    // reaches: tilted along the bore, the tool reaches in from the bore's end. Only where more
    // than a tenth of the patch is hidden: a few samples hidden where a face meets a wall beside
    // it are the rays' start off the surface, not an obstacle (the block's top face: 16 of 289).
    std::vector<std::size_t> blocked;
    for (std::size_t p = 0; p < np; ++p)
      if (10 * hidden[p][p] > positions[p].size()) blocked.push_back(p);
    std::vector<std::optional<Eigen::Vector3d>> around(blocked.size());
    tbb::parallel_for(std::size_t(0), blocked.size(), [&](std::size_t i) {
      const std::size_t p = blocked[i];
      std::size_t fewest = hidden[p][p];
      double best_low = -2;
      for (const Eigen::Vector3d& a : sphere) {
        const double l = smallest_dot(normals[p], a);
        if (l < threshold[p] || (around[i] && l <= best_low && fewest == 0)) continue;
        const std::size_t h = count_hidden(a, p, fewest + 1, nullptr);
        if (h < fewest || (h == fewest && around[i] && l > best_low)) around[i] = a, fewest = h, best_low = l;
      }
    });
    const std::size_t first_around = candidates.size();
    for (std::size_t i = 0; i < blocked.size(); ++i)
      if (around[i]) {
        own[blocked[i]] = candidates.size();
        candidates.push_back(*around[i]);
        add_low_row(*around[i]);
        hidden.emplace_back(np, 0);
        hidden_sum.emplace_back(np, Eigen::Vector3d::Zero());
      }
    measure_from(first_around);
  }
  const std::size_t nc = candidates.size();
  // can[c][p]: candidate c cuts patch p.
  std::vector<std::vector<char>> can(nc, std::vector<char>(np));
  for (std::size_t c = 0; c < nc; ++c)
    for (std::size_t p = 0; p < np; ++p) can[c][p] = c == own[p] || (low[c][p] >= threshold[p] && hidden[c][p] == 0);

  // Square: the axes away from the base and along the coordinate axes, and any other candidate
  // that is one of them.
  std::vector<char> square(nc, 0);
  for (std::size_t c = 0; c < nc; ++c)
    for (std::size_t k = np; k < first_sphere && !square[c]; ++k) square[c] = (candidates[c] - candidates[k]).norm() < 1e-9;
  std::vector<char> covered(np, 0);
  std::vector<std::size_t> chosen;
  for (std::size_t left = np; left > 0;) {
    std::size_t best = nc, best_count = 0;
    double best_low = -2;
    for (std::size_t c = 0; c < nc; ++c) {
      std::size_t count = 0;
      double worst = 2;
      for (std::size_t p = 0; p < np; ++p)
        if (!covered[p] && can[c][p]) ++count, worst = std::min(worst, low[c][p]);
      // A square axis (away from the base, or a coordinate axis: what a vise and an angle plate
      // give) counts kSquareBonus better in a tie: a machinist sets it up without a protractor.
      if (square[c]) worst += kSquareBonus;
      if (count > best_count || (count == best_count && count > 0 && worst > best_low + 1e-9))
        best = c, best_count = count, best_low = worst;
    }
    chosen.push_back(best);  // a patch's own direction always cuts it: best exists
    for (std::size_t p = 0; p < np; ++p)
      if (!covered[p] && can[best][p]) covered[p] = 1, --left;
  }

  std::vector<Setup> setups(chosen.size());
  for (std::size_t s = 0; s < chosen.size(); ++s) {
    Setup& st = setups[s];
    st.axis = candidates[chosen[s]];
    place_setup(st, points);
  }
  for (std::size_t p = 0; p < np; ++p) {
    std::size_t home = chosen.size();
    for (std::size_t s = 0; s < chosen.size(); ++s)
      if (can[chosen[s]][p] && (home == chosen.size() || low[chosen[s]][p] > low[chosen[home]][p])) home = s;
    setups[home].patches.push_back(static_cast<std::uint32_t>(p));
    setups[home].min_normal_dot = std::min(setups[home].min_normal_dot, low[chosen[home]][p]);
    if (const std::size_t h = hidden[chosen[home]][p]; h > 0) {
      setups[home].hidden_samples += h;
      setups[home].hidden_patches.push_back({static_cast<std::uint32_t>(p), h, hidden_sum[chosen[home]][p] / double(h)});
    }
  }
  // A setup every patch of which fits better elsewhere: dropped, the rest renumbered.
  std::erase_if(setups, [](const Setup& s) { return s.patches.empty(); });
  for (std::size_t s = 0; s < setups.size(); ++s) setups[s].name = std::to_string(s + 1) + ": " + axis_name(setups[s].axis);
  return setups;
}

nlohmann::json part_to_machine(const Setup& s) {
  nlohmann::json m = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) m.push_back({s.rotation(r, 0), s.rotation(r, 1), s.rotation(r, 2), s.translation[r]});
  return m;
}

nlohmann::json setups_report(const std::vector<Setup>& setups) {
  nlohmann::json list = nlohmann::json::array();
  for (const Setup& s : setups)
    list.push_back({{"name", s.name},
                    {"axis", {s.axis.x(), s.axis.y(), s.axis.z()}},
                    {"part_to_machine", part_to_machine(s)},
                    {"patches", s.patches},
                    {"min_normal_dot", s.min_normal_dot},
                    {"hidden_samples", s.hidden_samples},
                    {"hidden_patches", hidden_patches_report(s.hidden_patches)}});
  return list;
}

std::vector<Setup> setups_from_report(const nlohmann::json& report, std::size_t patches) {
  if (!report.contains("setups") || !report["setups"].is_array() || report["setups"].empty())
    throw std::invalid_argument("the setups report has no setups");
  std::vector<Setup> out;
  for (const auto& j : report["setups"]) {
    Setup s;
    s.name = j.value("name", "setup " + std::to_string(out.size() + 1));
    const auto& m = j.value("part_to_machine", nlohmann::json());
    const std::string bad = "setup '" + s.name + "': part_to_machine is not 3 rows [R|t]";
    if (!m.is_array() || m.size() != 3) throw std::invalid_argument(bad);
    for (int r = 0; r < 3; ++r) {
      if (!m[r].is_array() || m[r].size() != 4) throw std::invalid_argument(bad);
      for (int c = 0; c < 3; ++c) s.rotation(r, c) = m[r][c].get<double>();
      s.translation[r] = m[r][3].get<double>();
    }
    if ((s.rotation.transpose() * s.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
        s.rotation.determinant() < 0)
      throw std::invalid_argument("setup '" + s.name + "': part_to_machine's R is not a rotation");
    s.axis = s.rotation.transpose() * Eigen::Vector3d::UnitZ();
    for (const auto& p : j.value("patches", nlohmann::json::array())) {
      const auto k = p.get<std::uint32_t>();
      if (k >= patches)
        throw std::invalid_argument("setup '" + s.name + "': patch " + std::to_string(k) + " of " +
                                    std::to_string(patches));
      s.patches.push_back(k);
    }
    s.min_normal_dot = j.value("min_normal_dot", 1.0);
    s.hidden_samples = j.value("hidden_samples", std::size_t(0));
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace scallop
