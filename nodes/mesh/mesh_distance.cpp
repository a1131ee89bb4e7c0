#include "nodes/mesh/mesh_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace scallop {

std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& m) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Triangles = std::vector<Kernel::Triangle_3>;
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
  auto point = [](const Eigen::Vector3d& p) { return Kernel::Point_3(p.x(), p.y(), p.z()); };
  Triangles tris;
  tris.reserve(m.num_faces());
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k)
      tris.emplace_back(point(m.vertices[m.face(f)[0]]), point(m.vertices[m.face(f)[k]]),
                        point(m.vertices[m.face(f)[k + 1]]));
  std::vector<double> d(points.size(), std::numeric_limits<double>::infinity());
  if (tris.empty()) return d;
  Tree tree(tris.begin(), tris.end());
  tree.accelerate_distance_queries();
  tbb::parallel_for(std::size_t{0}, points.size(),
                    [&](std::size_t i) { d[i] = std::sqrt(tree.squared_distance(point(points[i]))); });
  return d;
}

}  // namespace scallop
