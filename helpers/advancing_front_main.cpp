// scallop-advancing-front IN OUT RADIUS_RATIO_BOUND BETA: CGAL's advancing-front surface
// reconstruction of the points in IN, its triangles written to OUT (mesh.reconstruct runs it).
//
// It runs as a process of its own because the front keeps its candidate edges in a std::set
// ordered by (criterion, address of the edge's record): where two criteria tie, the heap's
// layout decides, and inside scallop that layout depends on what ran before (the disk cache, the
// other parts of a batch). A fresh process starts from the same heap each time, so the same
// points give the same triangles.
//
// IN:  uint64 n, then n points as 3 float64 (little-endian, as this machine writes them).
// OUT: uint64 m, then m triangles as 3 uint64 point indices, in the order the front gave them.
// Exit status 0 when OUT was written, 1 (a message on stderr) otherwise.
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  if (argc != 5) {
    std::cerr << "usage: scallop-advancing-front IN OUT RADIUS_RATIO_BOUND BETA\n";
    return 1;
  }
  try {
    std::ifstream in(argv[1], std::ios::binary);
    std::uint64_t n = 0;
    if (!in.read(reinterpret_cast<char*>(&n), sizeof n)) throw std::runtime_error("cannot read the point count");
    std::vector<double> xyz(3 * n);
    if (!in.read(reinterpret_cast<char*>(xyz.data()), static_cast<std::streamsize>(xyz.size() * sizeof(double))))
      throw std::runtime_error("the file holds fewer than " + std::to_string(n) + " points");
    std::vector<Point> points(n);
    for (std::uint64_t i = 0; i < n; ++i) points[i] = Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    std::vector<std::array<std::size_t, 3>> triangles;
    CGAL::advancing_front_surface_reconstruction(points.begin(), points.end(), std::back_inserter(triangles),
                                                 std::stod(argv[3]), std::stod(argv[4]));
    std::ofstream out(argv[2], std::ios::binary);
    const std::uint64_t m = triangles.size();
    out.write(reinterpret_cast<const char*>(&m), sizeof m);
    for (const auto& t : triangles) {
      const std::uint64_t v[3] = {t[0], t[1], t[2]};
      out.write(reinterpret_cast<const char*>(v), sizeof v);
    }
    if (!out) throw std::runtime_error(std::string("cannot write ") + argv[2]);
  } catch (const std::exception& e) {
    std::cerr << "scallop-advancing-front: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
