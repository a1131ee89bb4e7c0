// Distances from points to a mesh's surface, and rays against it (CGAL's AABB tree): for reports
// that measure a reconstruction or a fitted surface against a mesh, and for what a tool axis can
// reach (surface.setups).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// points  #P by 3; mesh  any polygons (each fanned into triangles from its first corner).
// Returns #P unsigned distances to the nearest point of the mesh's faces, computed in parallel;
// all +infinity when the mesh has no face.
std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& mesh);

// origins, directions  #R rays (directions need not be unit). Returns, per ray, whether it meets
// one of the mesh's faces (a face through its origin counts: start the ray off the surface).
// Computed in parallel; all false when the mesh has no face.
std::vector<bool> rays_hit_mesh(const std::vector<Eigen::Vector3d>& origins, const std::vector<Eigen::Vector3d>& directions,
                                const Mesh& mesh);

}  // namespace scallop
