// Feature-preserving filtering of a triangle mesh's face normals by second-order total generalised
// variation: the normal step of MeshTGV (Liu, Li, Wang, Liu, Chen, "Mesh Total Generalized
// Variation for Denoising", IEEE TVCG 28(12) 2022, doi 10.1109/TVCG.2021.3088118), the denoising
// of the second method (papers/point-clouds-to-workpieces.md, "MeshTGV").
//
// TGV of second order (Bredies, Kunisch, Pock, "Total generalized variation", SIAM J. Imaging
// Sci. 3(3) 2010) of a field u is  min_W  alpha1 |grad u - W| + alpha0 |E W|: an auxiliary
// first-order field W takes up the smooth variation of u, so that only the variation W does not
// explain (jumps) costs at first order, and W itself pays for its own variation. Piecewise
// constant and piecewise linear fields are both cheap; noise is not. MeshTGV discretises this for
// the face normals N (piecewise constant over the triangles) with operators on faces and edges and
// minimises it with a data term by variable splitting and the augmented Lagrangian method (ALM).
// Its exact operators are not reproduced here (the paper's text was not at hand); this is a
// discretisation with the same structure, built so that both parts of TGV's kernel cost nothing:
// a plane (N constant, W = 0) and a sphere or cylinder, whose unit normal is an affine function
// of the position (N(x) = (x - o) / R: W = (I - N N^T) / R on the sphere).
//
//   faces f: unit normal N_f (3), area a_f, centroid c_f; noisy normals N0_f;
//            W_f (3 x 3): the gradient of the normal field on f (row k: grad of N_k)
//   edges e with two faces f, g: length l_e, d_e = c_f - c_g
//     first-order term:  (DN - AW)_e = N_f - N_g - (W_f + W_g)/2 d_e
//                        (the jump of the normals that the mean gradient does not predict)
//     second-order term: (DW)_e = W_f - W_g
//
//   min_{N, W}  sum_f a_f/2 |N_f - N0_f|^2 + alpha1 sum_e l_e |(DN - AW)_e|
//                                          + alpha0 sum_e l_e |(DW)_e|_F,
//   |N_f| = 1,  W_f N_f = 0 (W tangent to the surface).
// Lengths and areas are taken in units of the mean edge length, so the parameters do not depend
// on the mesh's size or resolution. Split P = DN - AW, Q = DW with scaled multipliers u, v and
// penalty r (both constraints); each ALM iteration solves the subproblems in turn:
//   N:  (diag(a) + r D^T L D) N = a N0 + r D^T L (P + u + AW),  then N_f <- N_f / |N_f|
//   W:  (r A^T L A + r D^T L D + r diag(a) P_N) W = r A^T L (DN - P - u) + r D^T L (Q + v),
//       then W_f <- W_f (I - N_f N_f^T)
//   P:  P_e = shrink((DN - AW)_e - u_e, alpha1 / r)    (closed form, per edge)
//   Q:  Q_e = shrink((DW)_e - v_e, alpha0 / r)
//   u += P - (DN - AW),   v += Q - DW
// with L = diag(l_e), shrink(x, t) = max(|x| - t, 0) x / |x|, P_N the penalty r a_f |W_f N_f|^2
// (it keeps the W system definite; the projection after it makes W exactly tangent). The two
// linear systems are sparse and symmetric positive definite; they are solved by preconditioned
// conjugate gradients (Jacobi for N, 3 x 3 blocks for W), warm-started from the previous
// iteration's N and W, a few steps each (an inexact ALM), matrix-free and in parallel. A direct
// factorisation (the paper's choice) was measured too slow at the sizes scallop meets: CHOLMOD's
// supernodal Cholesky of the N matrix alone of a 330 000-face mesh took 5.0 s, and each solve
// with its three right-hand sides 0.22 s (Eigen's SimplicialLDLT: 9.3 s and 0.23 s), against
// about 0.25 s of CPU for a whole ALM iteration (both subproblems) of a 400 000-face mesh here
// (bench/mesh_denoise_bench.cpp). Edges on the boundary (one face) carry no term.
//
// What was measured (tests/nodes/mesh/denoise_test.cpp):
//   - A sphere's normals cost nothing: a clean icosphere comes back within 0.001 of its radius.
//   - Flat sides are not quite free: the jumps at a cube's edges cost alpha1 each, and tilting
//     each side's normals slightly towards its neighbours (a faint dome) lowers them, so a clean
//     cube's filtered normals are turned by 1.0 degrees on average (1.5 at most); after the
//     vertex update its sides lie 0.36 degrees off away from the edges and its vertices moved by
//     up to 13 % of the edge spacing. This is the contrast loss of TV-type models
//     (Rudin-Osher-Fatemi) in TGV's form; bilateral filtering does not have it.
//   - alpha_ratio hardly matters at the default iteration counts: the second-order term's
//     multipliers stay below alpha0 in 50 iterations, so the penalty r rather than alpha0 is what
//     keeps W smooth (the results for ratios 2 to 50 agreed to 0.001 degrees on the test cube).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/mesh.h"

namespace scallop {

// The penalty taken when TgvOptions::penalty is 0, as a multiple of alpha1: on the test cube
// and sphere (tests/nodes/mesh/denoise_test.cpp) r between 6 and 8 alpha1 reached a given
// normal error in the fewest iterations; 2 alpha1 or 20 alpha1 needed two to three times more.
inline constexpr double kAutoPenalty = 7.0;

struct TgvOptions {
  double alpha1 = 0.3;       // weight of the first-order term (jumps the gradient field does not
                             // explain) against fidelity to the input normals: larger removes
                             // more noise and more small detail
  double alpha_ratio = 2.0;  // alpha0 / alpha1: the second-order term's weight relative to the
                             // first; larger keeps more bends as sharp edges, smaller lets
                             // them round off
  double penalty = 0;        // r, the ALM penalty on both constraints; 0: kAutoPenalty * alpha1
  int iterations = 50;       // ALM iterations at most
  double tolerance = 0.02;   // degrees; stop when the normals turned by less than this in one
                             // iteration (area-weighted mean)
  int cg_iterations = 8;     // conjugate-gradient steps on the N subproblem per iteration at most
  int w_cg_iterations = 2;   // the same on the W subproblem (W changes slowly: more steps
                             // hardly change the result, measured on the test cube)
  double cg_tolerance = 1e-3;  // relative residual at which a subproblem's CG stops earlier
};

struct TgvResult {
  std::vector<Eigen::Vector3d> normals;  // #F filtered unit normals
  int iterations = 0;                    // ALM iterations done
  double last_turn_mean_deg = 0;         // how far the normals turned in the last iteration:
  double last_turn_max_deg = 0;          // area-weighted mean and largest
  long long cg_steps = 0;                // conjugate-gradient steps in all (both subproblems)
};

// mesh      a triangle mesh (every face a triangle)
// edges     mesh_edges(mesh), every edge with at most 2 faces; geometry: face_geometry(mesh)
// progress  optional, called with the fraction done in [0, 1]
// Throws std::invalid_argument for a face that is not a triangle, an edge with 3 or more faces,
// alpha1 <= 0, alpha_ratio <= 0, penalty < 0, iterations < 0, cg_iterations or
// w_cg_iterations < 1, tolerance < 0.
TgvResult tgv_filter_normals(const Mesh& mesh, const MeshEdges& edges, const FaceGeometry& geometry,
                             const TgvOptions& options,
                             const std::function<void(double)>& progress = {});

}  // namespace scallop
