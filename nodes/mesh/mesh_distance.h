// Distances from points to a mesh's surface (CGAL's AABB tree), for reports that measure a
// reconstruction or a fitted surface against a mesh.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// points  #P by 3; mesh  any polygons (each fanned into triangles from its first corner).
// Returns #P unsigned distances to the nearest point of the mesh's faces, computed in parallel;
// all +infinity when the mesh has no face.
std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& mesh);

}  // namespace scallop
