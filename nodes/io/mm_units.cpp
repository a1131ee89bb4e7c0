#include "nodes/io/mm_units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "nodes/geom/kd_tree.h"

namespace scallop {
namespace {

std::string num(double v, const char* format = "%.3g") {
  char buf[32];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace

std::string out_of_range_point(const std::vector<Eigen::Vector3d>& P) {
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Eigen::Vector3d& p = P[i];
    if (p.allFinite() && p.cwiseAbs().maxCoeff() > kMaxCoordinateMm)
      return "point " + std::to_string(i) + " at (" + num(p.x()) + ", " + num(p.y()) + ", " + num(p.z()) +
             "): coordinates out of range (beyond 1e9 mm); the file is damaged or its scale is wrong";
  }
  return "";
}

CloudScale measure_scale(const std::vector<Eigen::Vector3d>& P, bool spacing) {
  std::vector<Eigen::Vector3d> F;
  F.reserve(P.size());
  for (const auto& p : P)
    if (p.allFinite()) F.push_back(p);
  CloudScale s;
  s.points = F.size();
  if (F.size() < 2) return s;
  Eigen::Vector3d lo = F[0], hi = F[0];
  for (const auto& p : F) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  s.extent = (hi - lo).maxCoeff();
  if (!spacing) return s;

  // Over kSubset points the tree is built on a random subset of kSubset, and its spacing scaled
  // by sqrt(kSubset / #F), as a surface's spacing scales with its density: a units warning needs
  // an order of magnitude, and a million-point tree costs half a second.
  double density_scale = 1;
  constexpr std::size_t kSubset = 200000;
  if (F.size() > kSubset) {
    std::mt19937_64 rng(1);
    for (std::size_t i = 0; i < kSubset; ++i)
      std::swap(F[i], F[i + std::uniform_int_distribution<std::size_t>(0, F.size() - 1 - i)(rng)]);
    density_scale = std::sqrt(static_cast<double>(kSubset) / static_cast<double>(F.size()));
    F.resize(kSubset);
  }
  const PointsAdaptor<Eigen::Vector3d> adaptor{F};
  KdTree<Eigen::Vector3d, 3> tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();
  // A sample is enough for an order of magnitude; duplicates (distance 0) are skipped, so that a
  // scan with repeated points still tells its spacing.
  constexpr std::size_t kSample = 1000, kK = 8;
  const std::size_t step = std::max<std::size_t>(1, F.size() / kSample);
  std::vector<double> nearest;
  std::uint32_t idx[kK];
  double d2[kK];
  for (std::size_t i = 0; i < F.size(); i += step) {
    const std::size_t found = tree.knnSearch(F[i].data(), std::min(kK, F.size()), idx, d2);
    for (std::size_t j = 0; j < found; ++j)
      if (d2[j] > 0) {
        nearest.push_back(std::sqrt(d2[j]));
        break;
      }
  }
  if (!nearest.empty()) {
    auto mid = nearest.begin() + nearest.size() / 2;
    std::nth_element(nearest.begin(), mid, nearest.end());
    s.spacing = *mid * density_scale;
  }
  return s;
}

std::string units_warning(const CloudScale& s, double scale, const std::string& scale_setting,
                          const std::string& noun) {
  if (s.points < 2 || s.extent <= 0) return "";
  const std::string what = "the " + noun + " is " + num(s.extent) + " mm across" +
                           (s.spacing > 0 ? " with points " + num(s.spacing) + " mm apart" : "");
  // A finishing job's part is millimetres to metres across, its points microns to millimetres apart.
  if (s.extent < 1 || (s.spacing > 0 && s.spacing < 1e-3))
    return what + ": is it in metres? coordinates are read as mm; set " + scale_setting + " to " + num(scale * 1000, "%.6g");
  if (s.spacing > 100)
    return what + ": is it in micrometres? coordinates are read as mm; set " + scale_setting + " to " +
           num(scale / 1000, "%.6g");
  return "";
}

void check_units(const NodeContext& ctx, const std::string& path, const std::vector<Eigen::Vector3d>& P, bool spacing,
                 const std::string& noun) {
  if (auto bad = out_of_range_point(P); !bad.empty()) throw InputError(path + ": " + bad);
  const std::string w = units_warning(measure_scale(P, spacing), ctx.number("scale"), ctx.node_id() + ".scale", noun);
  if (!w.empty()) ctx.warn(w);
}

}  // namespace scallop
