// Sharp edges put back into a triangle mesh that interpolates a cloud.
//
// A random sample of a part has no points on its edges, so the triangles of a reconstruction that
// interpolates the points (advancing front) join the two faces of an edge with a chamfer about a
// point spacing wide: 0.1 mm on a 200 000-point cloud of a 60 mm block, enough for a ball kept
// off that mesh to cut into the real edge. Following the idea of Attene, Falcidieno, Rossignac
// and Spagnuolo, "Edge-Sharpener: recovering sharp features in triangulations of non-adaptively
// re-meshed surfaces" (SGP 2003):
//   1. faces whose neighbours (all faces sharing a corner) turn by at most `smooth_angle` are
//      smooth; smooth faces joined across edges make regions (the part's faces), grown from the
//      flattest faces first, each keeping within min_angle / 2 of its first face's normal: no
//      two faces of a region turn by min_angle, so an edge always lies between two regions, even
//      where its two faces blend into each other elsewhere (a curved face is cut into several
//      regions, whose surfaces agree where they meet: no edge is made there);
//   2. a vertex of smooth faces of one region belongs to it; a vertex of none (the chamfer
//      band) to the region whose local surface it lies nearest (a quadric over the plane of that
//      region's vertices nearby: a plane's bias on a curved or twisted face would move edges);
//   3. where vertices of three regions meet, their surfaces each turning by min_angle or more
//      against the others there, the vertex nearest the point where the three meet is moved onto
//      it (a corner); an edge between vertices of two regions whose surfaces turn by min_angle or
//      more there is split where those surfaces meet (the point of that curve nearest the edge;
//      where a region has too few vertices there for a surface, a sliver of a piece of a curved
//      face, the surface its vertex lies nearest of the others' stands in, if that one meets the
//      other region's at an edge);
//   4. each triangle is cut at its new points, so the chamfer becomes the two faces meeting at
//      the edge.
// Where that curve passes beside a vertex rather than across an edge, the vertex is moved onto
// it, along its own face (the curve lies on both surfaces). A band vertex off every region's
// surface (by more than a tenth of a mean edge: not a point of the part but a hole's filling)
// moves onto its region's. No other vertex moves, and the surface
// keeps its pieces, holes and genus (closed stays closed). Where the moves turn a face over (a
// face facing against the one it was cut from, two faces folded onto each other, or one flattened
// onto a line), points that came out of order along an edge or past a corner are merged into
// one (the edge's point into the corner, a band vertex into the edge's point): the edge stays
// sharp. A move that would still turn a face over is made only in part.
#pragma once

#include <cstddef>

#include "nodes/types/mesh.h"

namespace scallop {

struct SharpenOptions {
  double smooth_angle = 15;   // deg: a face is smooth when every face sharing a corner turns less
  double min_angle = 15;      // deg: faces meeting at less than this are not an edge to restore
  double radius = 8;          // mean edge lengths: the neighbourhood of a local surface
  int min_region_faces = 10;  // smaller regions are noise, not faces of the part
};

// mesh           the sharpened mesh: the input's vertices first, in order (less those merged,
//                below: then also less any no face used), then the new ones;
//                face labels carried to the pieces of each face; vertex normals recomputed when
//                the input had them; its feature edges the part's edges it now has (both ends on
//                restored curves, corners or vertices already on two regions, the faces turning
//                by more than min_angle), any the input had replaced
// regions        smooth regions found (of at least min_region_faces faces; a curved face makes several)
// band_vertices  vertices on no smooth face, given a region by their distance to its plane
// split_edges    edges split on the curve where two regions' surfaces meet
// moved_vertices vertices moved onto that curve where it passes beside them (along their own
//                face), instead of a sliver split off an edge
// corners        vertices moved onto the point where three regions' surfaces meet
// skipped_edges  edges between two regions left whole: their surfaces turning by less than
//                min_angle there (pieces of one curved face) or meeting too far from the edge (more
//                than its length)
// projected_vertices  band vertices off every region's surface by 0.1 to 1 mean edge lengths (not
//                points of the part: a hole's filling), moved onto the nearest one's
// merged_vertices  vertices merged into a neighbour on the same edge of the part, or its corner,
//                since moving both turned a face over (and the merge turns or folds no other)
// flipped_edges  edges flipped where a face lay turned over across its longest edge with its
//                corners in place (three points of a face of the part nearly in a line), or where a
//                sliver with a corner on a restored edge (narrower than 0.05 of its longest edge)
//                is made wider by the flip
// held_back      moved or new vertices held short of their edge's line (and off the feature
//                edges), since all the way a face beside them would turn over: where the chamfer is
//                narrower than the move, or new points crowd along the line
// largest_held_back  the farthest one of them stays from the line (mm): the chamfer left there
// corners_refanned  corners whose vertex was held short, their faces within a few edges made
//                again as a fan from the corner (where the loop around them lies on its three faces)
// largest_offset the farthest a new point lies from the edge it splits, or a vertex moved (mm):
//                the deepest chamfer restored
// edge_length    the mean edge length of the input (mm)
struct SharpenResult {
  Mesh mesh;
  std::size_t regions = 0, band_vertices = 0, split_edges = 0, moved_vertices = 0, corners = 0, skipped_edges = 0;
  std::size_t merged_vertices = 0, held_back = 0, projected_vertices = 0, corners_refanned = 0, flipped_edges = 0;
  double largest_offset = 0, largest_held_back = 0, edge_length = 0;
};

// Throws std::invalid_argument for a face that is not a triangle, an index out of range or a
// non-finite vertex.
SharpenResult sharpen_edges(const Mesh& mesh, const SharpenOptions& options = {});

}  // namespace scallop
