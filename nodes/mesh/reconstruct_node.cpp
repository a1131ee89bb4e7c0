#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/reconstruct.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"

namespace scallop::mesh_nodes {

NodeDecl make_reconstruct_node() {
  NodeDecl d;
  d.type = "mesh.reconstruct";
  d.version = 3;  // 2: the advancing front's triangles in a fixed order (they changed from run to run); 3: the
                  // front in a process of its own (its ties no longer follow this process's heap)
  d.description =
      "a cloud -> a triangle mesh: advancing front (interpolates the points, keeps sharp edges; "
      "optional sharpness-aware bilateral smoothing first for noisy clouds; run as a process of its own, "
      "scallop-advancing-front, so the same cloud always gives the same mesh) or Poisson (watertight, "
      "rounds sharp edges, trimmed where it strays from the points) (CGAL)";
  d.input("cloud", "Cloud", "the points; normals needed for poisson and for smoothing")
      .output("mesh", "Mesh", "triangles, each component oriented like the cloud's normals (outward)")
      .output("report", "Report",
              "{method, points, vertices, faces, spacing (mm, mean to the 6 nearest), smooth_moved (mm, "
              "last bilateral pass), trimmed_faces, unused_points, distance {mean, p99, max} (mm, from "
              "each input point to the mesh), components, boundary_loops, genus, non_manifold_edges}")
      .param_choice("method", "advancing_front", {"advancing_front", "poisson"},
                    "advancing_front: every vertex is a cloud point, sharp edges kept; poisson: a "
                    "smooth watertight surface fitted to points and oriented normals");
  d.options<ReconstructOptions>()
      .integer("smooth_iterations", &ReconstructOptions::smooth_iterations, 0, 20, "",
                 "advancing_front: bilateral smoothing passes (CGAL bilateral_smooth_point_set) before "
                 "meshing; 2-3 on noisy scans, 0 on clean or already denoised clouds. Each pass moves "
                 "points onto their neighbours' tangent planes, so a curved surface shrinks by about "
                 "d^2 / 2R (d the neighbourhood's radius, R the surface's): fine on flat faces, keep "
                 "smooth_neighbors small on tightly curved parts")
      .integer("smooth_neighbors", &ReconstructOptions::smooth_neighbors, 4, 256, "", "neighbours of each bilateral fit")
      .number("sharpness_angle", &ReconstructOptions::sharpness_angle, 0.0, 90.0, "deg",
                   "bilateral smoothing: normals further apart than about this are treated as "
                   "across an edge and not averaged (smaller keeps edges sharper)")
      .number("radius_ratio_bound", &ReconstructOptions::radius_ratio_bound, 1.0, 1000.0, "",
                   "advancing_front: candidate triangles much larger than their neighbours are "
                   "refused above this ratio (larger fills bigger holes)")
      .number("beta", &ReconstructOptions::beta, 0.01, 1.57, "rad",
                   "advancing_front: half-angle of the wedge in which only the triangle's size counts")
      .number("trim_spacings", &ReconstructOptions::trim_spacings, 0.5, 1000.0, "spacings",
                   "poisson: faces farther than this from every point are removed (Poisson invents "
                   "surface where there are no points)")
      .number("poisson_approximation", &ReconstructOptions::poisson_approximation, 0.01, 10.0, "spacings",
                   "poisson: how far the mesh's triangles may stray from the fitted implicit surface "
                   "(smaller: finer triangles, slower)");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    ReconstructOptions o = ctx.options<ReconstructOptions>();
    o.method = ctx.text("method") == "poisson" ? ReconstructMethod::poisson : ReconstructMethod::advancing_front;
    ReconstructResult r;
    try {
      r = reconstruct_surface(cloud->points, cloud->normals, o,
                              [&](double f, const std::string& m) { ctx.progress(f, m); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    const MeshTopology t = mesh_topology(r.mesh, mesh_edges(r.mesh));
    if (t.components > 1)
      ctx.warn("the mesh has " + std::to_string(t.components) +
               " separate components (separate parts in the cloud, or gaps the reconstruction did not bridge)");
    Report report;
    report.data = {{"method", ctx.text("method")},
                   {"points", cloud->size()},
                   {"vertices", r.mesh.num_vertices()},
                   {"faces", r.mesh.num_faces()},
                   {"spacing", r.spacing},
                   {"smooth_moved", r.smooth_moved},
                   {"trimmed_faces", r.trimmed_faces},
                   {"unused_points", r.unused_points},
                   {"distance", {{"mean", r.distance_mean}, {"p99", r.distance_p99}, {"max", r.distance_max}}},
                   {"components", t.components},
                   {"boundary_loops", t.boundary_loops},
                   {"genus", t.genus},
                   {"non_manifold_edges", t.non_manifold_edges}};
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(r.mesh));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
