// mesh.denoise and mesh.sharp_edges on a large noisy mesh: the time and memory budget of issue 12
// (200 000 points -> denoised mesh with sharp edges in <= 30 s on the 2-core machine, so denoising
// a ~400 000-triangle mesh must take a few seconds).
//
// Standalone Google Benchmark program. The mesh is the tests' cube (tests/nodes/mesh/
// mesh_test_util.h): edge 1, SCALLOP_BENCH_CUBE_N squares a side (default 183: 401 868
// triangles, 200 936 vertices, spacing 0.0055), Gaussian noise along the vertex normals of 20 %
// of the spacing (as the tests' cube: 1 % of the edge at 20 squares). Each benchmark runs once
// (the work is seconds, not microseconds) and reports, besides the time, the faces' mean normal
// error against the true sides (away from the edges, degrees), the filter's iterations and the
// split between the normal filter and the vertex update.
//
//   ./build/mesh_denoise_bench                                   # all
//   /usr/bin/time -v ./build/mesh_denoise_bench --benchmark_filter=tgv   # peak memory of one
// SCALLOP_BENCH_THREADS=n caps oneTBB's threads.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <memory>

#include "nodes/mesh/denoise.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/sharp_edges.h"
#include "tests/nodes/mesh/mesh_test_util.h"

namespace {

using namespace scallop;

int cube_n() {
  const char* n = std::getenv("SCALLOP_BENCH_CUBE_N");
  return n ? std::atoi(n) : 183;
}

const Mesh& noisy_cube() {
  static const Mesh m = test::add_normal_noise(test::cube_mesh(cube_n()), 0.2 / cube_n(), 1);
  return m;
}

// Degrees, faces farther than 2 % of the edge from the cube's edges (11 spacings at n = 183).
double normal_error_deg(const Mesh& m) { return test::cube_normal_error_deg(m, 0.02); }

void denoise(benchmark::State& state, MeshDenoiseMethod method) {
  const Mesh& in = noisy_cube();
  MeshDenoiseOptions o;
  o.method = method;
  MeshDenoiseResult r;
  for (auto _ : state) r = denoise_mesh(in, o);
  state.counters["faces"] = static_cast<double>(in.num_faces());
  state.counters["error_in_deg"] = normal_error_deg(in);
  state.counters["error_out_deg"] = normal_error_deg(r.mesh);
  state.counters["iterations"] = r.iterations;
  state.counters["filter_s"] = r.filter_seconds;
  state.counters["vertex_s"] = r.vertex_seconds;
  const SharpEdges s = sharp_edges(r.mesh, mesh_edges(r.mesh), 50);
  state.counters["curves"] = static_cast<double>(s.curves.size());
  state.counters["corners"] = static_cast<double>(s.corners.size());
}

void sharp(benchmark::State& state) {
  const Mesh& in = test::cube_mesh(cube_n());
  SharpEdges s;
  for (auto _ : state) s = sharp_edges(in, mesh_edges(in), 50);
  state.counters["curves"] = static_cast<double>(s.curves.size());
}

BENCHMARK_CAPTURE(denoise, tgv, MeshDenoiseMethod::Tgv)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK_CAPTURE(denoise, bilateral, MeshDenoiseMethod::Bilateral)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(sharp)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  std::unique_ptr<tbb::global_control> threads;
  if (const char* n = std::getenv("SCALLOP_BENCH_THREADS"))
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::atoi(n));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
