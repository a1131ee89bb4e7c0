// Does mesh.cloud_envelope hold the part? The true part's surface sampled by area, each sample's
// signed distance to the outer mesh (how far it lies outside) and to the inner one (how far
// inside): what the certificate's gouge and scallop bounds rest on (issue 14, "Stop 52").
//
//   envelope_holds OUTER.ply INNER.ply MESH.ply TRUE_MESH [SCALE] [SAMPLES]
//
// OUTER/INNER: the node's outputs (io.write_mesh); MESH: the mesh it moved (their faces, to tell
// a face the moves turned over); TRUE_MESH: the part (OFF/STL/PLY) times SCALE (1); SAMPLES:
// 1 000 000. Prints, for each bound, how many samples lie beyond it by more than 1 um, 5 um and
// 20 um, and the farthest with where.
#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "nodes/io/read_mesh.h"
#include "nodes/mesh/mesh_distance.h"

using scallop::Mesh;

namespace {

std::vector<Eigen::Vector3d> sample_by_area(const Mesh& m, std::size_t n) {
  std::vector<double> area(m.num_faces());
  double total = 0;
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const std::uint32_t* c = m.face(f);
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k)
      area[f] += 0.5 * (m.vertices[c[k]] - m.vertices[c[0]]).cross(m.vertices[c[k + 1]] - m.vertices[c[0]]).norm();
    total += area[f];
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<Eigen::Vector3d> pts;
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    const std::uint32_t* c = m.face(f);
    const int count = int(area[f] / total * double(n) + U(rng));  // each face its share, rounded at random
    for (int i = 0; i < count; ++i) {
      // A fanned triangle picked by area, then a uniform point in it.
      double pick = U(rng) * area[f];
      std::size_t k = 1;
      for (; k + 2 < m.face_size(f); ++k) {
        const double a = 0.5 * (m.vertices[c[k]] - m.vertices[c[0]]).cross(m.vertices[c[k + 1]] - m.vertices[c[0]]).norm();
        if (pick < a) break;
        pick -= a;
      }
      double s = U(rng), t = U(rng);
      if (s + t > 1) s = 1 - s, t = 1 - t;
      pts.push_back(m.vertices[c[0]] + s * (m.vertices[c[k]] - m.vertices[c[0]]) + t * (m.vertices[c[k + 1]] - m.vertices[c[0]]));
    }
  }
  return pts;
}

void report(const char* what, const std::vector<Eigen::Vector3d>& pts, const std::vector<double>& beyond) {
  std::size_t over[3] = {0, 0, 0};
  std::size_t far = 0;
  for (std::size_t i = 0; i < beyond.size(); ++i) {
    over[0] += beyond[i] > 0.001, over[1] += beyond[i] > 0.005, over[2] += beyond[i] > 0.02;
    if (beyond[i] > beyond[far]) far = i;
  }
  std::printf("%s: %zu / %zu / %zu of %zu samples beyond by > 0.001 / 0.005 / 0.02 mm; farthest %.4f mm at (%.3f, %.3f, %.3f)\n",
              what, over[0], over[1], over[2], beyond.size(), beyond[far], pts[far].x(), pts[far].y(), pts[far].z());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: envelope_holds OUTER.ply INNER.ply MESH.ply TRUE_MESH [SCALE] [SAMPLES]\n");
    return 2;
  }
  try {
    const Mesh outer = scallop::read_mesh(argv[1]), inner = scallop::read_mesh(argv[2]), mesh = scallop::read_mesh(argv[3]);
    const Mesh truth = scallop::read_mesh(argv[4], argc > 5 ? std::stod(argv[5]) : 1.0);
    const std::vector<Eigen::Vector3d> pts = sample_by_area(truth, argc > 6 ? std::stoul(argv[6]) : 1000000);
    const scallop::MeshDistance to_outer(outer, &mesh), to_inner(inner, &mesh);
    std::vector<double> outside(pts.size()), inside(pts.size());
    tbb::parallel_for(std::size_t(0), pts.size(), [&](std::size_t i) {
      outside[i] = to_outer.signed_distance(pts[i]);
      inside[i] = -to_inner.signed_distance(pts[i]);
    });
    report("outside the outer mesh", pts, outside);
    report("inside the inner mesh", pts, inside);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "envelope_holds: %s\n", e.what());
    return 1;
  }
}
