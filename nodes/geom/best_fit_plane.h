// The least-squares plane of a set of points, shared by boundary ordering and boundary mapping.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace scallop {

// Least-squares plane of P: centroid c and unit normal n (smallest principal direction),
// oriented along the sum of N when N is not empty, else with n_z >= 0.
void best_fit_plane(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& N,
                    Eigen::Vector3d& c, Eigen::Vector3d& n);

}  // namespace scallop
