// The surface queries every later node repeats per sample: GridKnn2d's 20 and 64 nearest and
// HeightFieldModel::eval (with its uncertainty, as post.simulate asks), over a row-by-row grid
// of a 100 x 100 mm wavy patch sampled by 100 000 random points (spacing 0.32 mm; the grid's
// 0.08 mm is post.simulate's at r 2, h 0.05). Single-threaded; the figure is per query.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "nodes/geom/grid_knn_2d.h"
#include "nodes/geom/height_field_model.h"

namespace {

const std::vector<Eigen::Vector3d>& cloud() {
  static const std::vector<Eigen::Vector3d> P = [] {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> U(0, 100);
    std::vector<Eigen::Vector3d> out(100000);
    for (auto& p : out) {
      const double x = U(rng), y = U(rng);
      p = {x, y, 3 * std::sin(x / 7) * std::cos(y / 9)};
    }
    return out;
  }();
  return P;
}
const std::vector<double>& uncertainty() {
  static const std::vector<double> u(cloud().size(), 0.01);
  return u;
}

// The grid's places, row by row (what post.simulate and the guard's probes visit).
std::vector<Eigen::Vector2d> places() {
  std::vector<Eigen::Vector2d> q;
  for (double y = 0.5; y < 99.5; y += 2.0)
    for (double x = 0.5; x < 99.5; x += 0.08) q.push_back({x, y});
  return q;
}

// k 20: the height field's fits; 64: its edge test (the widest angular gap, at the rim).
void BM_GridKnn2d(benchmark::State& state) {
  const scallop::GridKnn2d grid(cloud());
  const auto q = places();
  const int k = int(state.range(0));
  std::uint32_t idx[64];
  double d2[64];
  for (auto _ : state)
    for (const auto& p : q) benchmark::DoNotOptimize(grid.query(p, k, idx, d2));
  state.SetItemsProcessed(state.iterations() * std::int64_t(q.size()));
}
BENCHMARK(BM_GridKnn2d)->Arg(20)->Arg(64)->Unit(benchmark::kMillisecond);

void BM_HeightFieldEval(benchmark::State& state) {
  const scallop::HeightFieldModel model(cloud(), 20, &uncertainty());
  const auto q = places();
  for (auto _ : state)
    for (const auto& p : q) {
      double z, u;
      Eigen::Vector3d n;
      benchmark::DoNotOptimize(model.eval(p.x(), p.y(), z, n, true, &u));
    }
  state.SetItemsProcessed(state.iterations() * std::int64_t(q.size()));
}
BENCHMARK(BM_HeightFieldEval)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
