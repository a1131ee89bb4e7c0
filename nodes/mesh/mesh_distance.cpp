#include "nodes/mesh/mesh_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace scallop {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Kernel::Point_3 point(const Eigen::Vector3d& p) { return Kernel::Point_3(p.x(), p.y(), p.z()); }

// Each polygon fanned from its first corner.
Triangles triangles(const Mesh& m) {
  Triangles tris;
  tris.reserve(m.num_faces());
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k)
      tris.emplace_back(point(m.vertices[m.face(f)[0]]), point(m.vertices[m.face(f)[k]]),
                        point(m.vertices[m.face(f)[k + 1]]));
  return tris;
}

}  // namespace

struct MeshDistance::Impl {
  Triangles tris;
  Tree tree;
};

MeshDistance::MeshDistance(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->tris = triangles(mesh);
  if (impl_->tris.empty()) return;
  impl_->tree.insert(impl_->tris.begin(), impl_->tris.end());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

MeshDistance::~MeshDistance() = default;

double MeshDistance::operator()(const Eigen::Vector3d& p) const {
  if (impl_->tris.empty()) return std::numeric_limits<double>::infinity();
  return std::sqrt(impl_->tree.squared_distance(point(p)));
}

double MeshDistance::ray_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& d) const {
  if (impl_->tris.empty()) return std::numeric_limits<double>::infinity();
  const Kernel::Ray_3 ray(point(p), Kernel::Direction_3(d.x(), d.y(), d.z()));
  const auto hit = impl_->tree.first_intersection(ray);
  if (!hit) return std::numeric_limits<double>::infinity();
  if (const Kernel::Point_3* q = boost::get<Kernel::Point_3>(&hit->first))
    return std::sqrt(CGAL::squared_distance(*q, ray.source()));
  return 0;  // the ray runs along a face from p
}

std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& m) {
  const MeshDistance distance(m);
  std::vector<double> d(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { d[i] = distance(points[i]); });
  return d;
}

}  // namespace scallop
