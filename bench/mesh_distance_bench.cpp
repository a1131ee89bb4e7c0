// What a distance query to a part's mesh costs (MeshDistance: the certificate's gouge check, the
// programs' clearance, the setups' reach all ask it): ball centres r off the faces, asked signed
// and unsigned, along short moves as post.simulate_part asks them, and whether each goes straight
// up clear (a pass end, a rest setup): least_along against clear_along.
//
//   mesh_distance_bench MESH [SCALE] [R]     (default scale 1, r = 2 mm)
//
// Prints the mesh's triangles, microseconds per query and per move.
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "nodes/io/read_mesh.h"
#include "nodes/mesh/mesh_distance.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: mesh_distance_bench MESH [SCALE] [R]\n");
    return 2;
  }
  const double scale = argc > 2 ? std::atof(argv[2]) : 1.0, r = argc > 3 ? std::atof(argv[3]) : 2.0;
  const scallop::Mesh mesh = scallop::read_mesh(argv[1], scale);
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  const Clock::time_point built = Clock::now();
  const scallop::MeshDistance distance(mesh);
  std::printf("%zu faces, tree built in %.3f s\n", mesh.num_faces(), seconds(built));

  // Ball centres: a random point of a random face (area-weighted), r along its normal, outward.
  std::vector<double> area(mesh.num_faces());
  std::vector<Eigen::Vector3d> normal(mesh.num_faces());
  for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
    const auto& v = mesh.vertices;
    const Eigen::Vector3d n = (v[mesh.face(f)[1]] - v[mesh.face(f)[0]]).cross(v[mesh.face(f)[2]] - v[mesh.face(f)[0]]);
    area[f] = n.norm(), normal[f] = n.normalized();
  }
  std::mt19937 rng(1);
  std::discrete_distribution<std::size_t> face(area.begin(), area.end());
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> centres;
  for (int k = 0; k < 20000; ++k) {
    const std::size_t f = face(rng);
    double a = unit(rng), b = unit(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const auto& v = mesh.vertices;
    const Eigen::Vector3d p = v[mesh.face(f)[0]] + a * (v[mesh.face(f)[1]] - v[mesh.face(f)[0]]) +
                              b * (v[mesh.face(f)[2]] - v[mesh.face(f)[0]]);
    centres.push_back(p + r * normal[f]);
  }
  double sum = 0;
  Clock::time_point t = Clock::now();
  for (const auto& c : centres) sum += distance(c);
  std::printf("unsigned: %.2f us per query\n", 1e6 * seconds(t) / double(centres.size()));
  t = Clock::now();
  for (const auto& c : centres) sum += distance.signed_distance(c);
  std::printf("signed:   %.2f us per query\n", 1e6 * seconds(t) / double(centres.size()));
  // Moves of 0.5 mm from each centre along a random direction, sampled every 0.07 mm.
  std::normal_distribution<double> gauss;
  std::size_t evaluations = 0;
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    Eigen::Vector3d where;
    sum += distance.least_along(centres[k], centres[k] + 0.5 * d, 0.07, r - 0.005, 1e-5, where, evaluations);
  }
  std::printf("moves:    %.2f us per move, %.1f distances each\n", 1e6 * seconds(t) / 5000, double(evaluations) / 5000);
  // The same moves unsigned as post.setup_programs keeps them off the part: least_along sampled
  // every r / 4 to 1e-4, against least_on_segment's one search.
  std::vector<Eigen::Vector3d> ends(5000);
  for (auto& e : ends) e = 0.5 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  std::vector<double> sampled(5000), exact(5000);
  evaluations = 0;
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    Eigen::Vector3d where;
    sampled[k] = distance.least_along(centres[k], centres[k] + ends[k], r / 4, r - 0.00125, 1e-4, where, evaluations, false);
  }
  std::printf("moves, unsigned, least_along:      %.2f us per move, %.1f distances each\n", 1e6 * seconds(t) / 5000,
              double(evaluations) / 5000);
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    Eigen::Vector3d where;
    exact[k] = distance.least_on_segment(centres[k], centres[k] + ends[k], where);
  }
  std::printf("moves, unsigned, least_on_segment: %.2f us per move\n", 1e6 * seconds(t) / 5000);
  double below = 0, above = 0;  // least_along's bound against the exact least, under the floor
  for (std::size_t k = 0; k < 5000; ++k)
    if (exact[k] < r - 0.00125) below = std::max(below, exact[k] - sampled[k]), above = std::max(above, sampled[k] - exact[k]);
  std::printf("  under the floor, least_along lower than the exact least by up to %.2g, higher by up to %.2g\n", below, above);
  // Verticals from each centre to 1 mm over the mesh's top, floor r - 0.00125 (e = 0.005):
  // sampled every r / 4 and bounded (least_along), or marched (clear_along).
  double top = -1e300;
  for (const auto& v : mesh.vertices) top = std::max(top, v.z());
  const double floor = r - 0.00125;
  std::vector<char> sampled_clear(5000), marched_clear(5000);
  evaluations = 0;
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    Eigen::Vector3d where;
    const Eigen::Vector3d up(centres[k].x(), centres[k].y(), std::max(top + r + 1, centres[k].z()));
    sampled_clear[k] = distance.least_along(centres[k], up, r / 4, floor, 1e-4, where, evaluations, false) >= floor;
  }
  std::printf("verticals, least_along: %.2f us each, %.1f distances each\n", 1e6 * seconds(t) / 5000,
              double(evaluations) / 5000);
  evaluations = 0;
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    const Eigen::Vector3d up(centres[k].x(), centres[k].y(), std::max(top + r + 1, centres[k].z()));
    marched_clear[k] = distance.clear_along(centres[k], up, r / 4, floor, &evaluations);
  }
  // Where they differ, the least is within least_along's precision (1e-4) of the floor: its
  // bound may fall under the floor there, or clear_along may stop short of proving it.
  std::size_t only_marched = 0, only_sampled = 0, clear = 0;
  for (std::size_t k = 0; k < 5000; ++k)
    only_marched += marched_clear[k] && !sampled_clear[k], only_sampled += sampled_clear[k] && !marched_clear[k],
        clear += marched_clear[k];
  double least_where_differ = 1e300;  // their least, to 1e-9
  for (std::size_t k = 0; k < 5000; ++k)
    if (marched_clear[k] != sampled_clear[k]) {
      Eigen::Vector3d where;
      std::size_t n = 0;
      const Eigen::Vector3d up(centres[k].x(), centres[k].y(), std::max(top + r + 1, centres[k].z()));
      least_where_differ = std::min(least_where_differ, distance.least_along(centres[k], up, r / 4, r, 1e-9, where, n, false));
    }
  if (only_marched + only_sampled > 0)
    std::printf("where they differ the least is %.9f, the floor %.9f\n", least_where_differ, floor);
  std::printf("verticals, clear_along: %.2f us each, %.1f distances each; %zu of 5000 clear; clear by it alone %zu, "
              "by least_along alone %zu\n",
              1e6 * seconds(t) / 5000, double(evaluations) / 5000, clear, only_marched, only_sampled);
  // Balls dropped along -z from 1 mm over the top at 5 000 random places of the mesh's box (a rest
  // raster's drops): the exact touch (touch_along, one ray) against sphere tracing, steps of the
  // distance less r until under 1e-6 (post.setup_programs before stop 62).
  double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300, bottom = 1e300;
  for (const auto& v : mesh.vertices)
    lo_x = std::min(lo_x, v.x()), hi_x = std::max(hi_x, v.x()), lo_y = std::min(lo_y, v.y()), hi_y = std::max(hi_y, v.y()),
    bottom = std::min(bottom, v.z());
  std::vector<Eigen::Vector3d> starts(5000);
  for (auto& c : starts) c = {lo_x + unit(rng) * (hi_x - lo_x), lo_y + unit(rng) * (hi_y - lo_y), top + r + 1};
  const double fall = top - bottom + 2 * r + 2;
  std::vector<double> traced(5000), touched(5000);
  std::size_t steps = 0;
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) {
    Eigen::Vector3d c = starts[k];
    double drop = 0;
    for (int it = 0; it < 400 && drop < fall; ++it, ++steps) {
      const double step = std::min(distance(c) - r, fall - drop);
      if (!(step > 1e-6)) break;
      c.z() -= step, drop += step;
    }
    traced[k] = drop;
  }
  std::printf("drops, sphere tracing: %.2f us each, %.1f distances each\n", 1e6 * seconds(t) / 5000, double(steps) / 5000);
  t = Clock::now();
  for (std::size_t k = 0; k < 5000; ++k) touched[k] = distance.touch_along(starts[k], -Eigen::Vector3d::UnitZ(), r, fall);
  const double touch_us = 1e6 * seconds(t) / 5000;
  // The exact touch against the traced landing: the tracing stops where the ball grazes the part
  // within 1e-6 of r (beside a wall) and the ball goes on down; between the two it stays r off.
  double deeper = 0, shallower = 0, between = INFINITY;
  for (std::size_t k = 0; k < 5000; ++k) {
    if (!(touched[k] < fall)) continue;
    deeper = std::max(deeper, touched[k] - traced[k]), shallower = std::max(shallower, traced[k] - touched[k]);
    if (touched[k] - traced[k] > 1e-6) {
      Eigen::Vector3d where;
      between = std::min(between, distance.least_on_segment(starts[k] - traced[k] * Eigen::Vector3d::UnitZ(),
                                                            starts[k] - touched[k] * Eigen::Vector3d::UnitZ(), where));
    }
  }
  std::printf("drops, touch_along: %.2f us each; it lands up to %.2g lower than the tracing (between them the ball "
              "keeps %.9f from the part), %.2g higher\n", touch_us, deeper, between, shallower);
  // Rays straight up from the same 5 000 starts lowered to where they touch (a ball over the part:
  // whether the part is above it, as keep_off_part asks at every ball and move).
  t = Clock::now();
  std::size_t met = 0;
  for (std::size_t k = 0; k < 5000; ++k)
    met += std::isfinite(distance.ray_distance(starts[k] - std::min(touched[k], fall) * Eigen::Vector3d::UnitZ(),
                                               Eigen::Vector3d::UnitZ()));
  std::printf("rays up, ray_distance: %.2f us each, %zu of 5000 meet the part\n", 1e6 * seconds(t) / 5000, met);
  return sum == 42 ? 1 : 0;  // keeps the sums alive
}
