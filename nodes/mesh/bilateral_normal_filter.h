// Bilateral filtering of a triangle mesh's face normals: the baseline of mesh.denoise.
//
// Zheng, Fu, Au, Tai, "Bilateral Normal Filtering for Mesh Denoising", IEEE TVCG 17(10) 2011,
// the local, iterative scheme: in each iteration every face normal becomes
//   n_i <- normalise( sum_{j in N(i)} A_j W_s(|c_i - c_j|) W_r(|n_i - n_j|) n_j ),
//   W_s(x) = exp(-x^2 / (2 sigma_s^2)),   W_r(x) = exp(-x^2 / (2 sigma_r^2)),
// N(i) the faces sharing a vertex with face i (i included), A_j their areas, c_j their
// centroids; all faces at once (Jacobi), from the previous iteration's normals. sigma_s is by
// default the mean distance between the centroids of faces sharing an edge (the paper's
// choice). Faces across a sharp edge differ in normal by much more than sigma_r and hardly
// mix; noise within sigma_r averages out.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/mesh.h"

namespace scallop {

struct BilateralOptions {
  double sigma_r = 0.35;  // range weight's width, on |n_i - n_j| (0.35 ~ 20 degrees between
                          // normals); the paper uses 0.2 .. 0.6
  double sigma_s = 0;     // mm; spatial weight's width; 0: the mean distance between the
                          // centroids of faces sharing an edge
  int iterations = 20;    // filtering iterations
};

struct BilateralResult {
  std::vector<Eigen::Vector3d> normals;  // #F filtered unit normals (zero where the input's is)
  int iterations = 0;
  double sigma_s = 0;  // mm, used
};

// mesh      a triangle (or polygon) mesh
// edges     mesh_edges(mesh); around: vertex_faces(mesh); geometry: face_geometry(mesh)
// progress  optional, called with the fraction done in [0, 1]
// Throws std::invalid_argument for sigma_r <= 0, sigma_s < 0, iterations < 0.
BilateralResult bilateral_filter_normals(const Mesh& mesh, const MeshEdges& edges,
                                         const VertexFaces& around, const FaceGeometry& geometry,
                                         const BilateralOptions& options,
                                         const std::function<void(double)>& progress = {});

}  // namespace scallop
