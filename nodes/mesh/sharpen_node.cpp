#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/sharpen.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_sharpen_node() {
  NodeDecl d;
  d.type = "mesh.sharpen";
  d.version = 11;
  d.description =
      "sharp edges put back into a triangle mesh that interpolates a cloud (advancing front): the "
      "chamfer its triangles cut across each edge is split where the two faces' local surfaces (quadrics) meet, "
      "a vertex the line passes beside is moved onto it, and the vertex nearest a corner of three "
      "faces onto the point where their surfaces meet (after Attene et al., Edge-Sharpener, 2003)";
  d.input("mesh", "Mesh", "triangles, e.g. mesh.reconstruct's then mesh.repair's")
      .output("mesh", "Mesh", "the same surface with its edges and corners restored: the input's vertices (less any merged, below), then the new ones; its "
              "feature edges the part's edges it now has")
      .output("report", "Report",
              "{regions (smooth faces joined, each within min_angle / 2 of its flattest face: a curved face makes several), band_vertices (on no smooth face: given the region whose "
              "plane they lie on), projected_vertices (band vertices off every region's surface by 0.1 to 1 mean edges, a hole's filling: moved onto their region's), split_edges, moved_vertices (onto an edge's line passing beside them), corners (vertices moved onto the point where three faces meet), skipped_edges (surfaces turning by less than min_angle there, or meeting far "
              "off), merged_vertices (merged into a neighbour on an edge where moving both turned a face over, or closer than a tenth of a mean edge to it along the edge), corners_refanned (corners whose vertex was held short: the faces within a few edges made again as a fan from the corner), flipped_edges (where a face lay turned over across its longest edge, its corners in place, or a sliver on a restored edge was made wider), held_back (vertices moved only part of the way, since all of it would turn a face over), "
              "largest_held_back (mm, the chamfer left there), largest_offset (mm, the deepest chamfer restored), edge_length (mm, mean), vertices, faces}");
  d.options<SharpenOptions>()
      .number("smooth_angle", &SharpenOptions::smooth_angle, 0.1, 90, "deg",
              "a face is smooth when every face sharing a corner with it turns by less than this")
      .number("min_angle", &SharpenOptions::min_angle, 1, 179, "deg",
              "faces meeting at less than this are not an edge to restore")
      .number("radius", &SharpenOptions::radius, 1, 100, "edge lengths",
              "the neighbourhood each local surface is fitted over")
      .integer("min_region_faces", &SharpenOptions::min_region_faces, 1, 1000000, "",
               "smooth regions with fewer faces are noise, not faces of the part");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    const SharpenOptions o = ctx.options<SharpenOptions>();
    SharpenResult r;
    try {
      r = sharpen_edges(*mesh, o);
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("mesh.sharpen: ") + e.what());
    }
    Report report;
    report.data = {{"regions", r.regions},          {"band_vertices", r.band_vertices},
                   {"projected_vertices", r.projected_vertices},
                   {"split_edges", r.split_edges},  {"moved_vertices", r.moved_vertices},
                   {"corners", r.corners},          {"corners_refanned", r.corners_refanned},
                   {"skipped_edges", r.skipped_edges}, {"merged_vertices", r.merged_vertices},
                   {"flipped_edges", r.flipped_edges}, {"held_back", r.held_back},
                   {"largest_held_back", r.largest_held_back}, {"largest_offset", r.largest_offset},
                   {"edge_length", r.edge_length},  {"vertices", r.mesh.num_vertices()},
                   {"faces", r.mesh.num_faces()}};
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(r.mesh));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
