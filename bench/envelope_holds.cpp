// Does mesh.cloud_envelope hold the part? The true part's surface sampled as the judge samples it, each sample's
// signed distance to the outer mesh (how far it lies outside) and to the inner one (how far
// inside): what the certificate's gouge and scallop bounds rest on (issue 14, "Stop 52").
//
//   envelope_holds OUTER.ply INNER.ply MESH.ply TRUE_MESH [SCALE] [SAMPLES]
//
// OUTER/INNER: the node's outputs (io.write_mesh); MESH: the mesh it moved (their faces, to tell
// a face the moves turned over); TRUE_MESH: the part (OFF/STL/PLY) times SCALE (1), or with
// CLOUD=1 a cloud whose points are the places; SAMPLES: at most, 1 000 000. Prints, for each
// bound, how many samples lie beyond it by more than 1 um, 5 um and 20 um, and the farthest with
// where; then the places beyond by more than 5 um, gathered within 1 mm of each other: how many,
// and the farthest of each.
#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <string>
#include <vector>

#include "nodes/io/read_cloud.h"
#include "nodes/io/read_mesh.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/post/part_samples.h"

using scallop::Mesh;

namespace {

// The part's surface as verify_part.py samples it (post/part_samples.h), at most n samples.
std::vector<Eigen::Vector3d> samples_of(const Mesh& m, std::size_t n) {
  const std::vector<scallop::PartTriangle> tris = scallop::part_triangles(m);
  double area = 0;
  for (const auto& t : tris) area += 0.5 * (t.b - t.a).cross(t.c - t.a).norm();
  std::vector<Eigen::Vector3d> pts;
  for (const auto& s : scallop::sample_part(tris, scallop::part_sample_spacing(tris, std::sqrt(area / double(n)), n)))
    pts.push_back(s.p);
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
  struct Place {
    std::size_t farthest, count;
  };
  std::vector<Place> places;
  for (std::size_t i = 0; i < beyond.size(); ++i) {
    if (!(beyond[i] > 0.005)) continue;
    Place* near = nullptr;
    for (Place& p : places)
      if ((pts[p.farthest] - pts[i]).norm() < 1.0) near = &p;
    if (!near) {
      places.push_back({i, 1});
      continue;
    }
    ++near->count;
    if (beyond[i] > beyond[near->farthest]) near->farthest = i;
  }
  for (const Place& p : places)
    std::printf("  %zu samples near (%.3f, %.3f, %.3f), by up to %.4f mm\n", p.count, pts[p.farthest].x(),
                pts[p.farthest].y(), pts[p.farthest].z(), beyond[p.farthest]);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: envelope_holds OUTER.ply INNER.ply MESH.ply TRUE_MESH [SCALE] [SAMPLES]\n");
    return 2;
  }
  try {
    const Mesh outer = scallop::read_mesh(argv[1]), inner = scallop::read_mesh(argv[2]), mesh = scallop::read_mesh(argv[3]);
    const double scale = argc > 5 ? std::stod(argv[5]) : 1.0;
    // CLOUD=1: the fourth file is a cloud, and its points are the places.
    const char* cloud = std::getenv("CLOUD");
    const std::vector<Eigen::Vector3d> pts =
        cloud && std::string(cloud) == "1"
            ? scallop::read_cloud(argv[4], scale).points
            : samples_of(scallop::read_mesh(argv[4], scale), argc > 6 ? std::stoul(argv[6]) : 1000000);
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
