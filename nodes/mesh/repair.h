// Repairing a polygon soup into a consistently oriented manifold mesh, with CGAL's
// Polygon_mesh_processing (only repair.cpp includes CGAL).
#pragma once

#include <cstddef>

#include "nodes/types/mesh.h"

namespace scallop {

struct RepairOptions {
  // Orient each closed component so that the mesh bounds a volume: normals point out of the
  // material (an outer shell's outward, a cavity's into the cavity).
  bool orient_outward = true;
  // Closed components whose surfaces cross (solids of an assembly that overlap) replaced by
  // their union (merge_solids.h); needs orient_outward.
  bool merge_overlapping = true;
  // Holes of at most this many border edges are closed with triangles (CGAL's
  // triangulate_and_refine_hole): the gaps an interpolating reconstruction leaves in a closed
  // part's surface. 0: none (an open part's border stays; it is far longer).
  int fill_holes = 0;
  // Slivers mended, their size in mean edge lengths (CGAL's remove_almost_degenerate_faces): a
  // face whose shortest edge is under this and a quarter of its longest loses that edge (its ends
  // merged), a face with a corner over 160 degrees no higher than this is flipped across its
  // longest edge. Two points of a random cloud 0.01 edges apart make such faces, and a move of either
  // beside an edge of the part turns them over (mesh.sharpen). The surface moves by at most this.
  // 0: none (a CAD mesh's long thin triangles are its shape).
  double slivers = 0;
};

// What repair_mesh changed, step by step (each count 0 on a clean, consistently oriented mesh).
struct RepairReport {
  // Polygon soup clean-up (CGAL's repair_polygon_soup, its steps in its order):
  std::size_t points_merged = 0;              // vertices at exactly the place of an earlier one
  std::size_t faces_simplified = 0;           // faces that lost a corner repeating the one before
  std::size_t pinched_faces_split = 0;        // faces through one place twice, split in two
  std::size_t degenerate_faces_removed = 0;   // faces left with fewer than 3 corners
  std::size_t duplicate_faces_removed = 0;    // faces on the same corners as another, either way round
  std::size_t isolated_vertices_removed = 0;  // vertices on no face
  // Consistent orientation (orient_polygon_soup):
  std::size_t faces_reversed = 0;             // to agree with the faces beside them
  std::size_t non_manifold_edges_cut = 0;     // edges with 3 or more faces, cut apart
  // Vertices added where the faces around a point do not form one fan (a bow tie, the ends of a
  // cut edge): by orient_polygon_soup, then duplicate_non_manifold_vertices.
  std::size_t non_manifold_vertices_split = 0;
  // On the mesh:
  std::size_t borders_stitched = 0;           // pairs of border edges joined (stitch_borders)
  std::size_t holes_filled = 0;               // holes closed (fill_holes)
  std::size_t holes_left = 0;                 // holes longer than fill_holes, or that CGAL could not close
  std::size_t slivers_found = 0;              // faces that were slivers by options.slivers
  std::size_t slivers_left = 0;               // of those, left (CGAL declined the change)
  std::size_t faces_turned_outward = 0;       // faces of closed components reversed (orient_to_bound_a_volume)
  std::size_t solids_merged = 0;              // closed components merged into one they cross (their union)
  std::size_t solids_not_merged = 0;          // crossing ones left apart (one intersects itself)
};

// soup  the input: any vertices and polygon faces (3 or more corners), in any orientation, with
//       duplicates, repeated corners, non-manifold edges and vertices; must have a face.
// Returns the repaired mesh: vertices and faces renumbered (vertices in order of first use as
// CGAL keeps them), every face with 3 or more distinct corners, quads and other polygons kept
// as they are (Surface_mesh holds polygons), each component consistently oriented, manifold;
// closed components bound a volume when options.orient_outward, and those that cross are one
// (their union) when options.merge_overlapping too. Vertex normals, face labels
// and feature edges are not carried over: repair comes before the steps that set them.
// Faces of no area with distinct corners (collinear ones) stay: mesh_topology counts them.
// Throws std::invalid_argument for a soup without faces or with a corner past the vertices,
// std::runtime_error when CGAL cannot make a polygon mesh of it.
Mesh repair_mesh(const Mesh& soup, const RepairOptions& options, RepairReport& report);

}  // namespace scallop
