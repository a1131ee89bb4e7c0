#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/repair.h"
#include "nodes/mesh/topology_report.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_repair_node() {
  NodeDecl d;
  d.type = "mesh.repair";
  d.version = 3;  // 2: crossing solids merged into their union; 3: slivers
  d.description =
      "repairs a polygon soup with CGAL: merges duplicate points, drops degenerate and duplicate faces, orients "
      "consistently, stitches borders, splits non-manifold edges and vertices, turns closed parts outward, merges solids that cross "
      "into their union (an assembly exported as one STL)";
  d.input("mesh", "Mesh", "any vertices and polygon faces (triangles, quads, mixed), in any orientation")
      .output("mesh", "Mesh",
              "manifold, each component consistently oriented, closed ones outward; quads kept; vertices and faces "
              "renumbered, so vertex normals, face labels and feature edges are dropped")
      .output("report", "Report",
              "{changes: {points_merged, faces_simplified, pinched_faces_split, degenerate_faces_removed, "
              "duplicate_faces_removed, isolated_vertices_removed, faces_reversed, non_manifold_edges_cut, "
              "non_manifold_vertices_split, borders_stitched, holes_filled, holes_left, slivers_found, slivers_left, faces_turned_outward, solids_merged, solids_not_merged}, "
              "before, after: the topology as io.read_mesh reports it}")
      .param_bool("orient_outward", true,
                  "orient each closed component so that the mesh bounds a volume (normals out of the material)")
      .param_bool("merge_overlapping", true,
                  "replace closed components whose surfaces cross by their union (CGAL corefinement); needs "
                  "orient_outward")
      .param_int("fill_holes", 0, 0, 1000000, "edges",
                 "holes with at most this many border edges are closed with triangles (the gaps an interpolating "
                 "reconstruction leaves in a closed part); 0: none")
      .param_float("slivers", 0.0, 0, 0.5, "mean edge lengths",
                    "slivers mended (CGAL's remove_almost_degenerate_faces): an edge shorter than this (and a quarter of "
                    "its face's longest) collapsed, a face with a corner over 160 degrees and no higher than this flipped; "
                    "the surface moves by at most this. For a reconstruction from a random cloud, whose near points make "
                    "faces that moving either turns over; 0 (a CAD mesh's thin triangles are its shape): none");
  d.run = [](NodeContext& ctx) {
    auto in = ctx.input<Mesh>("mesh");
    RepairOptions options;
    options.orient_outward = ctx.flag("orient_outward");
    options.merge_overlapping = ctx.flag("merge_overlapping");
    options.fill_holes = static_cast<int>(ctx.integer("fill_holes"));
    options.slivers = ctx.number("slivers");
    RepairReport r;
    Mesh out;
    try {
      out = repair_mesh(*in, options, r);
    } catch (const std::exception& e) {
      throw NodeError(e.what());
    }
    Report report;
    report.data["changes"] = {{"points_merged", r.points_merged},
                              {"faces_simplified", r.faces_simplified},
                              {"pinched_faces_split", r.pinched_faces_split},
                              {"degenerate_faces_removed", r.degenerate_faces_removed},
                              {"duplicate_faces_removed", r.duplicate_faces_removed},
                              {"isolated_vertices_removed", r.isolated_vertices_removed},
                              {"faces_reversed", r.faces_reversed},
                              {"non_manifold_edges_cut", r.non_manifold_edges_cut},
                              {"non_manifold_vertices_split", r.non_manifold_vertices_split},
                              {"borders_stitched", r.borders_stitched},
                              {"holes_filled", r.holes_filled},
                              {"holes_left", r.holes_left},
                              {"slivers_found", r.slivers_found},
                              {"slivers_left", r.slivers_left},
                              {"faces_turned_outward", r.faces_turned_outward},
                              {"solids_merged", r.solids_merged},
                              {"solids_not_merged", r.solids_not_merged}};
    if (r.solids_not_merged > 0)
      ctx.warn(std::to_string(r.solids_not_merged) +
               " closed components cross each other but could not be merged (one intersects itself): faces of one "
               "lie inside another, and what is measured against the part is not exact there");
    report.data["before"] = topology_report(*in);
    report.data["after"] = topology_report(out);
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(out));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
