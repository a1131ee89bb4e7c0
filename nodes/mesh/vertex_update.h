// Vertex positions fitted to filtered face normals: the second step of normal-filtering mesh
// denoising (mesh.denoise, both methods).
//
// Sun, Rosin, Martin, Langbein, "Fast and effective feature-preserving mesh denoising", IEEE
// TVCG 13(5) 2007, section 4: the vertices minimise
//   sum_f sum_{(i,j) edge of f} (n_f . (x_j - x_i))^2,
// each edge of a face made orthogonal to the face's filtered normal n_f, by the gradient-descent
// iteration
//   x_i <- x_i + 1/|F_i| sum_{f in F_i} n_f (n_f . (c_f - x_i)),
// F_i the faces around vertex i, c_f the centroid of f at the current positions: each vertex
// moves towards the planes through its faces' centroids with their filtered normals. The same
// update is used after MeshTGV (Liu et al. 2021, which follows Zhang et al.) and bilateral
// normal filtering (Zheng et al. 2011). Only motion along the normals is induced, so the
// tangential sampling stays.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/mesh.h"

namespace scallop {

// mesh        the mesh (polygons of any size; its vertex positions are the start)
// around      vertex_faces(mesh)
// normals     #F filtered unit face normals; a zero normal leaves its face out of the update
// iterations  updates (>= 0); all vertices move at once in each (Jacobi), in parallel
// progress    optional, called with the fraction done in [0, 1] after each iteration
// Returns the #V new positions (a vertex on no face stays where it is).
std::vector<Eigen::Vector3d> update_vertices(const Mesh& mesh, const VertexFaces& around,
                                             const std::vector<Eigen::Vector3d>& normals,
                                             int iterations,
                                             const std::function<void(double)>& progress = {});

}  // namespace scallop
