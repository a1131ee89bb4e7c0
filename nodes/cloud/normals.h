// Point normals by local PCA, with consistent orientation.
//
// The normal of a point is the eigenvector of the smallest eigenvalue of the covariance of the
// point and its k neighbours (Hoppe, DeRose, Duchamp, McDonald, Stuetzle, "Surface reconstruction
// from unorganized points", SIGGRAPH 1992, section 3.2). Orientation is either towards +Z (height
// fields, the normal case for 3-axis parts) or propagated along a minimum spanning tree of the
// neighbour graph with edge cost 1 - |n_i . n_j| (Hoppe et al. 1992, section 3.3), so that
// orientation flows across flat regions before it crosses high curvature.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

enum class NormalOrientation {
  Up,   // n_z >= 0 everywhere: right for height fields (surfaces machined from above)
  Mst,  // consistent propagation over the MST of the KNN graph, seeded +Z at the highest point
  Auto  // Mst, then all flipped if more normals point down (n_z < 0) than up (n_z > 0)
};

// "up", "mst", "auto"; throws std::invalid_argument otherwise.
NormalOrientation parse_normal_orientation(const std::string& name);

// P     #P by 3 positions (mm)
// nbrs  k >= 2 neighbours of each of the #P points (e.g. compute_knn(P, k)); all k are used
// surface_variation  if not null, resized to #P and set to lambda0 / (lambda0 + lambda1 +
//       lambda2) of each covariance (Pauly, Gross, Kobbelt, "Efficient simplification of point-
//       sampled surfaces", 2002): 0 on a plane, up to 1/3 for isotropic noise.
// Returns #P unit normals, unoriented (sign as the eigen solver gives it).
// Degenerate neighbourhoods are an error, not a guess: when the point and its neighbours are
// coincident or collinear (lambda1 <= 1e-12 lambda2) the normal is undefined, and
// std::invalid_argument names the first such point and suggests cloud.clean or a larger k.
// Also throws std::invalid_argument when nbrs does not match P (size, k < 2, index range).
std::vector<Eigen::Vector3d> pca_normals(const std::vector<Eigen::Vector3d>& P,
                                         const Neighborhoods& nbrs,
                                         std::vector<double>* surface_variation = nullptr);

// Flips every normal with n_z < 0. Normals with n_z == 0 (vertical walls) are left as they are.
void orient_normals_up(std::vector<Eigen::Vector3d>& N);

// Orients N consistently by Prim's minimum spanning tree over the symmetrised KNN graph with
// weights 1 - |n_i . n_j|: the highest point (largest z, lowest index on ties) is oriented +Z and
// every other normal is flipped to agree with its tree parent (n_child . n_parent >= 0). A KNN
// graph with several connected components is handled component by component, each seeded the
// same way at its own highest point. Sequential, O(#P k log(#P k)).
void orient_normals_mst(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nbrs,
                        std::vector<Eigen::Vector3d>& N);

// pca_normals followed by the orientation `mode` (see NormalOrientation). Same errors.
std::vector<Eigen::Vector3d> estimate_normals(const std::vector<Eigen::Vector3d>& P,
                                              const Neighborhoods& nbrs, NormalOrientation mode,
                                              std::vector<double>* surface_variation = nullptr);

}  // namespace scallop
