// Feature-preserving denoising of a triangle mesh (mesh.denoise): its face normals filtered, then
// its vertices moved to fit them (vertex_update.h). Two filters:
//   tgv        MeshTGV (Liu et al. 2021): second-order total generalised variation of the normals,
//              augmented Lagrangian method (tgv_normal_filter.h); flat faces stay flat, smooth
//              bends stay smooth, sharp edges stay sharp
//   bilateral  bilateral normal filtering (Zheng et al. 2011), local and iterative
//              (bilateral_normal_filter.h): the baseline
#pragma once

#include <functional>
#include <string>

#include "nodes/mesh/bilateral_normal_filter.h"
#include "nodes/mesh/tgv_normal_filter.h"
#include "nodes/types/mesh.h"

namespace scallop {

enum class MeshDenoiseMethod { Tgv, Bilateral };

struct MeshDenoiseOptions {
  MeshDenoiseMethod method = MeshDenoiseMethod::Tgv;
  TgvOptions tgv;
  BilateralOptions bilateral;
  int vertex_iterations = 30;  // vertex updates towards the filtered normals (Sun et al. 2007)
};

struct MeshDenoiseResult {
  Mesh mesh;  // the input's faces, labels and feature edges; new vertex positions; vertex
              // normals recomputed (area-weighted) when the input had them
  int iterations = 0;  // normal-filter iterations done
  double last_turn_mean_deg = 0, last_turn_max_deg = 0;  // tgv: how far the normals turned in
                                                          // its last iteration (mean, largest)
  long long cg_steps = 0;      // tgv: conjugate-gradient steps of its two subproblems in all
  double move_mean = 0, move_max = 0;  // mm, how far the vertices on faces moved
  // degrees, area-weighted mean (and largest) angle between each face's normal before and after
  double normal_change_mean_deg = 0, normal_change_max_deg = 0;
  double filter_seconds = 0, vertex_seconds = 0;
};

// mesh      a triangle mesh: no face of another size, no edge with 3 or more faces, finite
//           coordinates (faces without area are allowed: their normals come from their
//           neighbours under tgv, and they are left out of the vertex update)
// progress  optional, called with the fraction done in [0, 1]
// Throws std::invalid_argument with the reason, e.g. "the mesh is empty (no faces)",
// "12 of 20 faces are not triangles: triangulate the mesh first", "3 edges have 3 or more faces:
// run mesh.repair first", "vertex 7 has a non-finite coordinate", or a bad option.
MeshDenoiseResult denoise_mesh(const Mesh& mesh, const MeshDenoiseOptions& options,
                               const std::function<void(double)>& progress = {});

}  // namespace scallop
