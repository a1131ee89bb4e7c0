#include "nodes/geom/kmeans.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

namespace scallop {
namespace {

// A draw in [0, 1) from the generator's raw 32-bit output: std::uniform_real_distribution is not
// specified bit for bit, so it could differ between standard libraries.
double uniform(std::mt19937& rng) { return (static_cast<double>(rng()) + 0.5) / 4294967296.0; }

// Index of the nearest centre (ties to the lower index) and its squared distance.
std::pair<int, double> nearest(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& centres) {
  int best = 0;
  double d2 = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < centres.size(); ++c) {
    const double d = (p - centres[c]).squaredNorm();
    if (d < d2) d2 = d, best = static_cast<int>(c);
  }
  return {best, d2};
}

// Draws an index with probability proportional to mass (whose sum is total > 0).
std::size_t draw(const std::vector<double>& mass, double total, std::mt19937& rng) {
  const double target = uniform(rng) * total;
  double run = 0;
  for (std::size_t i = 0; i < mass.size(); ++i) {
    run += mass[i];
    if (run > target && mass[i] > 0) return i;
  }
  // Rounding left the target past the last sum: the last point with mass.
  std::size_t i = mass.size();
  while (i > 0 && mass[i - 1] <= 0) --i;
  return i - 1;
}

std::vector<Eigen::Vector3d> seed_centres(const std::vector<Eigen::Vector3d>& P, const std::vector<double>& w, int k,
                                          std::mt19937& rng) {
  std::vector<Eigen::Vector3d> centres{P[draw(w, std::accumulate(w.begin(), w.end(), 0.0), rng)]};
  std::vector<double> d2(P.size()), mass(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) d2[i] = (P[i] - centres[0]).squaredNorm();
  while (static_cast<int>(centres.size()) < k) {
    double total = 0;
    for (std::size_t i = 0; i < P.size(); ++i) total += mass[i] = w[i] * d2[i];
    if (!(total > 0)) break;  // every weighted point sits on a centre: fewer distinct points than k
    centres.push_back(P[draw(mass, total, rng)]);
    for (std::size_t i = 0; i < P.size(); ++i) d2[i] = std::min(d2[i], (P[i] - centres.back()).squaredNorm());
  }
  return centres;
}

KMeansResult lloyd(const std::vector<Eigen::Vector3d>& P, const std::vector<double>& w,
                   std::vector<Eigen::Vector3d> centres, int max_iterations) {
  KMeansResult r;
  r.label.assign(P.size(), -1);
  auto relabel = [&] {
    bool changed = false;
    for (std::size_t i = 0; i < P.size(); ++i) {
      const int c = nearest(P[i], centres).first;
      changed |= c != r.label[i];
      r.label[i] = c;
    }
    return changed;
  };
  for (int it = 0;; ++it) {
    // The labels are always those of the final centres, also when the iterations run out.
    if (!relabel() || it == max_iterations) break;
    std::vector<Eigen::Vector3d> sum(centres.size(), Eigen::Vector3d::Zero());
    std::vector<double> mass(centres.size(), 0.0);
    for (std::size_t i = 0; i < P.size(); ++i) {
      sum[r.label[i]] += w[i] * P[i];
      mass[r.label[i]] += w[i];
    }
    // A cluster that lost all its weight keeps its centre (it may win points back or stay empty).
    for (std::size_t c = 0; c < centres.size(); ++c)
      if (mass[c] > 0) centres[c] = sum[c] / mass[c];
  }
  r.centre = std::move(centres);
  return r;
}

// Drops empty clusters, sums weights and sizes, orders heaviest first, and relabels.
void finish(const std::vector<Eigen::Vector3d>& P, const std::vector<double>& w, KMeansResult& r) {
  const std::size_t C = r.centre.size();
  std::vector<double> weight(C, 0.0);
  std::vector<std::size_t> size(C, 0);
  for (std::size_t i = 0; i < P.size(); ++i) weight[r.label[i]] += w[i], ++size[r.label[i]];
  std::vector<int> order;
  for (std::size_t c = 0; c < C; ++c)
    if (size[c] > 0) order.push_back(static_cast<int>(c));
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    if (weight[a] != weight[b]) return weight[a] > weight[b];
    return std::lexicographical_compare(r.centre[a].data(), r.centre[a].data() + 3, r.centre[b].data(),
                                        r.centre[b].data() + 3);
  });
  std::vector<int> rank(C, -1);
  KMeansResult out;
  for (std::size_t n = 0; n < order.size(); ++n) {
    rank[order[n]] = static_cast<int>(n);
    out.centre.push_back(r.centre[order[n]]);
    out.weight.push_back(weight[order[n]]);
    out.size.push_back(size[order[n]]);
  }
  out.label.resize(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) {
    out.label[i] = rank[r.label[i]];
    out.inertia += w[i] * (P[i] - out.centre[out.label[i]]).squaredNorm();
  }
  r = std::move(out);
}

}  // namespace

KMeansResult kmeans(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& weights,
                    const KMeansOptions& options) {
  if (points.empty()) throw std::invalid_argument("k-means of no points");
  if (options.k < 1) throw std::invalid_argument("k-means needs k >= 1");
  if (!weights.empty() && weights.size() != points.size())
    throw std::invalid_argument("k-means: " + std::to_string(weights.size()) + " weights for " +
                                std::to_string(points.size()) + " points");
  std::vector<double> w = weights.empty() ? std::vector<double>(points.size(), 1.0) : weights;
  for (double x : w)
    if (!(x >= 0)) throw std::invalid_argument("k-means: a weight is negative or not a number");
  if (!(std::accumulate(w.begin(), w.end(), 0.0) > 0)) throw std::invalid_argument("k-means: every weight is 0");

  KMeansResult best;
  bool have = false;
  for (int r = 0; r < std::max(1, options.restarts); ++r) {
    std::mt19937 rng(options.seed + static_cast<std::uint32_t>(r));
    KMeansResult run = lloyd(points, w, seed_centres(points, w, options.k, rng), options.max_iterations);
    finish(points, w, run);
    if (!have || run.inertia < best.inertia) best = std::move(run), have = true;
  }
  return best;
}

}  // namespace scallop
