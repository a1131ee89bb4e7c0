// Fewer triangles, same shape and feature curves (mesh.simplify), before QuadriFlow.
//
// QuadriFlow's time grows with its input, not with the quads asked: 23-34 s for 3000 quads of a
// 400 000-triangle mesh from a 200 000-point cloud, 4-6 s from the 13 000-triangle fandisk. The
// quads are about 3 mm across, so a mesh a few times finer than them says all QuadriFlow can use.
// CGAL's edge collapse (Surface_mesh_simplification) with Garland-Heckbert plane quadrics (the
// sum of squared distances to the faces an edge's ends had, Garland & Heckbert 1997) picks each
// collapse and the new point; Bounded_normal_change_placement refuses a collapse that would turn
// a face over. Feature edges (the input's feature_edges, mesh.sharp_edges) and border edges are
// never collapsed and their vertices never move, so the feature curves stay exactly where the
// input had them (its sharp edges keep every vertex). Measured on 200 000-point clouds (fandisk,
// block, sigma 0.02 mm; 400 000 triangles to 80 000): the collapse takes 8-11 s and QuadriFlow
// 5-6 s instead of 23-34 s, the fitted surfaces as close to the truth as without it (p99 0.27 and
// 0.56 mm against 0.32 and 0.55). CGAL's isotropic remeshing to the same count, tried in its
// place, was no closer (0.40 and 0.53 mm).
#pragma once

#include <cstddef>

#include "nodes/types/mesh.h"

namespace scallop {

struct SimplifyOptions {
  int target_faces = 80000;  // stop at this many triangles (or when nothing can collapse)
  int max_valence = 12;      // no collapse leaves a vertex with more edges than this
};

struct SimplifyReport {
  std::size_t faces_before = 0, faces_after = 0;
  std::size_t vertices_before = 0, vertices_after = 0;
  std::size_t feature_edges = 0;  // kept (they are never collapsed)
  std::size_t border_edges = 0;   // kept likewise
  double max_distance = 0;        // mm, largest distance from an input vertex to the output
  std::size_t max_valence = 0;    // the most edges at one vertex of the output
};

// mesh  a triangle mesh, manifold (mesh.repair), any feature_edges. A mesh with no more than
// target_faces triangles comes back unchanged. No collapse leaves a vertex with more than
// max_valence edges (a vertex that had more keeps them), so fewer may go than asked. Returns the
// simplified mesh: triangles, vertices renumbered, its feature_edges the input's (renumbered), no
// normals or labels. Throws
// std::invalid_argument when a face is not a triangle or the mesh is not manifold.
Mesh simplify_mesh(const Mesh& mesh, const SimplifyOptions& options, SimplifyReport& report);

}  // namespace scallop
