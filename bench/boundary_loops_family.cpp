// cloud.boundary_order on a family of plates whose loop is hard to follow: 648 plates 40 x 30 mm
// (9 600 random points, as 50 000 on the catalog's plane) with a slit down from the top edge
// (1.2 / 0.8 / 1.8 mm wide, 12 / 18 / 24 mm deep, at x = 10) and the boundary points missing along
// 2.5 mm of the top edge 6, 12 or 20 mm right of it, over 24 scans. A plate counts as missed when
// there is more than one loop, the loop encloses more than 60 mm^2 off the plate's area less the
// slit, or it leaves off more than 2 of the top edge's boundary points between the slit and the
// gap (the loop then cuts across the plate). Prints each miss and the count.
//   build/boundary_loops_family
#include <cstdio>
#include <random>
#include <vector>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/boundary_order.h"
#include "nodes/cloud/knn.h"

int main() {
  using scallop::PointCloud;
  int misses = 0, runs = 0;
  for (unsigned seed = 1; seed < 25; ++seed)
    for (double depth : {12.0, 18.0, 24.0})
      for (double gap_x : {16.0, 22.0, 30.0})
        for (double width : {0.8, 1.2, 1.8}) {
          std::mt19937 rng(seed);
          std::uniform_real_distribution<double> ux(0, 40), uy(0, 30);
          PointCloud c;
          while (c.size() < 9600) {
            const Eigen::Vector3d p(ux(rng), uy(rng), 0);
            if (std::abs(p.x() - 10) < width / 2 && p.y() > 30 - depth) continue;
            c.points.push_back(p);
            c.normals.push_back(Eigen::Vector3d::UnitZ());
          }
          const auto nb = scallop::compute_knn(c.points, 16);
          auto b = scallop::detect_boundary(c.points, c.normals, nb, M_PI / 2);
          for (std::size_t i = 0; i < c.size(); ++i)
            if (b[i] && c.points[i].x() > gap_x && c.points[i].x() < gap_x + 2.5 && c.points[i].y() > 28) b[i] = 0;
          const auto loops = scallop::order_boundary_loops(c.points, c.normals, nb, b);
          std::vector<char> on_loop(c.size(), 0);
          for (int i : loops[0]) on_loop[i] = 1;
          int stretch = 0, kept = 0;
          for (std::size_t i = 0; i < c.size(); ++i)
            if (b[i] && c.points[i].x() > 12 && c.points[i].x() < gap_x - 1 && c.points[i].y() > 29.5)
              ++stretch, kept += on_loop[i];
          const double area = scallop::projected_loop_area(c.points, loops[0], Eigen::Vector3d::Zero(),
                                                           Eigen::Vector3d::UnitZ());
          ++runs;
          if (kept < stretch - 2 || std::abs(area - (1200 - width * depth)) > 60 || loops.size() != 1) {
            ++misses;
            std::printf("missed: scan %u, slit %.1f x %.0f mm, gap at x %.0f: %d of %d top-edge points on the loop, "
                        "area %.0f mm^2, %zu loops\n",
                        seed, width, depth, gap_x, kept, stretch, area, loops.size());
          }
        }
  std::printf("%d of %d plates missed\n", misses, runs);
  return 0;
}
