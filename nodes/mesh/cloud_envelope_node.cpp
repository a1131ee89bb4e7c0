#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/cloud_envelope.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

namespace {

// The value below which a fraction q of xs lies (xs copied).
double quantile(std::vector<double> xs, double q) {
  if (xs.empty()) return 0;
  const std::size_t i = std::min(xs.size() - 1, std::size_t(q * double(xs.size())));
  std::nth_element(xs.begin(), xs.begin() + i, xs.end());
  return xs[i];
}


}  // namespace

NodeDecl make_cloud_envelope_node() {
  NodeDecl d;
  d.type = "mesh.cloud_envelope";
  // 2: faces folded onto a neighbour leave the side to the rays (MeshDistance::signed_distance);
  // 3: with exact feature edges, vertices at no point bounded by their points' local surfaces;
  // 4: and the allowance beside them leaves out the faces with a corner so bounded;
  // 5: a face's points that a quadric misses by more than a quarter spacing (was one) fit no surface
  // 6: points beyond the outer or inner mesh: faces its moves turned over leave the side to the rays;
  //    the bend allowance over the gap a face bridges in the cloud where it is wider than the spacing
  // 7: points beyond: faces turned more than 10 degrees leave the side to the rays (was 90); the
  //    points' spread added to both bounds (spread, 1)
  // 8: with exact feature edges, the bend allowance is the crease each face may hide between its
  //    corners (its longest edge / 2 x tan of half the turn around it), crest out, valley in, and no
  //    allowance for the gaps faces bridge (the crease's chord counts them); a vertex's face of the
  //    part is the faces reached within its points' search radius (was joined over the whole mesh)
  //  10: with exact feature edges, a face whose points (over it and a spacing around) fit one
  //    local surface gets at most that surface's bulge over the face plus 3 misfits (was the crease
  //    its neighbours' turn allows alone)
  //  11: and the same for two planes meeting in a line fit to those points (a crease softer than
  //    the feature edges, a CAD mesh's facets), seeded by the two faces around that turn most
  //  12: a face with a corner at no point (off the feature edges) keeps its crease allowance (was
  //    left out with the faces on a feature edge)
  //  13: the better fit of the quadric and the crease's two planes decides a face's allowance (was
  //    the smaller), the crease's height over the face exact (was a grid of sixths, plus a tenth)
  //  14: with exact feature edges, a vertex whose side's points fit no quadric (two faces of the
  //    part: an edge's line broken off) is bounded by two planes meeting in a line where those fit
  //    them (was the spacing's allowance)
  //  15: ... only where v's faces on that side follow the two planes (14 let a bevel's face cut the
  //    part between its corners: the block x 5's cloud, 3 samples 0.03 mm outside the outer mesh)
  //  16: a point on a corner that lies on a feature edge belongs to neither face (it counted on
  //    whichever face the nearest-face search returned, and that differed between machines)
  d.version = 16;
  d.description =
      "how far the real part may lie off a mesh made from its cloud (a bevelled edge, smoothed noise): each "
      "vertex's bound from its k nearest points' distances and the mesh's bend, the mesh pushed out (what balls are "
      "kept off and gouge is measured against) and in (what scallop is measured from) by it";
  d.input("mesh", "Mesh", "the mesh made from the cloud, faces outward (closed: inside and outside are clear)")
      .input("cloud", "Cloud", "the points the mesh was made from (after cloud.clean)")
      .output("outer", "Mesh", "the mesh, each vertex moved out along its normal by the farthest of its points outside")
      .output("inner", "Mesh", "the mesh, each vertex moved in by the farthest of its points inside")
      .output("report", "Report",
              "{points, vertices, neighbours, spacing_median, max_gap, outward_max, outward_p99, outward_median, "
              "outward_max_at, inward_max, inward_p99, inward_median, inward_max_at, surface_uncertainty (the larger "
              "maximum), residual_min, residual_max (the points' signed distances), bend_allowance_max (spacing x "
              "the sine of the largest angle to the faces within 3 spacings, with exact_feature_edges the largest crease a face "
              "may hide, half its longest edge x the tangent of half the turn around it; or a wider gap a face bridges in the "
              "cloud x the tangent of its angle to its neighbours), points_beyond and beyond_max (points outside the outer mesh or inside the "
              "inner one, the farthest), unsupported_vertices, unsupported_at, vertices_checked, off_points_max and vertices_without_surface "
              "(with exact_feature_edges: vertices on a feature edge or at no point, the largest bound their points' local "
              "surfaces gave them, and those where a face's points fit no surface, too few or misfit above a quarter spacing, "
              "given the bend allowance instead)}")
      .param_int("neighbours", 16, 1, 1000, "", "points per vertex (the largest of their deviations bounds the part there)")
      .param_float("max_gap", 0, 0, 1000, "mm",
                   "a vertex farther than this from every point is unsupported (reported); 0: 4 times the median "
                   "point spacing")
      .param_float("bend", 1, 0, 10, "spacings",
                   "the bend allowance: where the mesh bends, the part may bend sharper between its points by up to "
                   "this many median spacings times the sine of the bend, or as many gaps a face bridges in the cloud "
                   "times the tangent of its bend against its neighbours (1 for a reconstruction that bevels edges)")
      .param_float("spread", 1, 0, 10, "standard deviations",
                   "added to both bounds at each vertex: this many standard deviations of its points' distances about "
                   "their mean (the noise; 0 on a mesh through its points): the largest of 16 noisy deviations reaches "
                   "only about 1.8 above their mean, and where the noise hides the part's shape (a mild edge the "
                   "denoising rounds) the part may stand above that")
      .param_bool("exact_feature_edges", false,
                  "the mesh's feature edges are the part's own (mesh.sharpen's restored edges) and its other vertices "
                  "points of the part: the bend allowance is the crease a face may hide between its corners (half its "
                  "longest edge x the tangent of half the largest angle between it and the faces sharing a corner, "
                  "outward for a crest, inward for a valley), none at a vertex on a feature edge. A vertex at "
                  "no point (a restored edge's or corner's) is bounded instead by its height over the local surface of "
                  "the points on each face of the part around it, plus 3 times that fit's largest residual");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    auto cloud = ctx.input<PointCloud>("cloud");
    CloudEnvelope e;
    try {
      e = cloud_envelope(*mesh, cloud->points, int(ctx.integer("neighbours")), ctx.number("max_gap"), ctx.number("bend"),
                         ctx.flag("exact_feature_edges"), ctx.number("spread"));
    } catch (const std::invalid_argument& ex) {
      throw NodeError(std::string("mesh.cloud_envelope: ") + ex.what());
    }
    const std::size_t at_out = std::max_element(e.out.begin(), e.out.end()) - e.out.begin();
    const std::size_t at_in = std::max_element(e.in.begin(), e.in.end()) - e.in.begin();
    const std::size_t at_gap = std::max_element(e.gap.begin(), e.gap.end()) - e.gap.begin();
    const auto [rmin, rmax] = std::minmax_element(e.residual.begin(), e.residual.end());
    Report report;
    report.data = {{"points", cloud->size()},
                   {"vertices", mesh->num_vertices()},
                   {"neighbours", ctx.integer("neighbours")},
                   {"spacing_median", e.spacing_median},
                   {"max_gap", e.max_gap},
                   {"outward_max", e.out[at_out]},
                   {"outward_p99", quantile(e.out, 0.99)},
                   {"outward_median", quantile(e.out, 0.5)},
                   {"outward_max_at", json_xyz(mesh->vertices[at_out])},
                   {"inward_max", e.in[at_in]},
                   {"inward_p99", quantile(e.in, 0.99)},
                   {"inward_median", quantile(e.in, 0.5)},
                   {"inward_max_at", json_xyz(mesh->vertices[at_in])},
                   {"surface_uncertainty", std::max(e.out[at_out], e.in[at_in])},
                   {"residual_min", *rmin},
                   {"residual_max", *rmax},
                   {"bend_allowance_max", e.bend_allowance_max},
                   {"points_beyond", e.points_beyond},
                   {"beyond_max", e.beyond_max},
                   {"unsupported_vertices", e.unsupported},
                   {"vertices_checked", e.vertices_checked},
                   {"off_points_max", e.off_points_max},
                   {"vertices_without_surface", e.vertices_without_surface},
                   {"unsupported_at", e.unsupported ? json_xyz(mesh->vertices[at_gap]) : nlohmann::json()}};
    if (e.unsupported > 0) {
      char text[300];
      std::snprintf(text, sizeof text,
                    "%zu vertices lie farther than %.3g mm from every point (up to %.3g mm, at %.2f %.2f %.2f): the "
                    "mesh there is not measured by the cloud (a filled hole?), its bounds there are a guess",
                    e.unsupported, e.max_gap, e.gap[at_gap], mesh->vertices[at_gap].x(), mesh->vertices[at_gap].y(),
                    mesh->vertices[at_gap].z());
      ctx.warn(text);
    }
    ctx.set("report", std::move(report));
    ctx.set("outer", std::move(e.outer));
    ctx.set("inner", std::move(e.inner));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
