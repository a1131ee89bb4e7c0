#include <chrono>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/mesh/denoise.h"
#include "nodes/types/document.h"
#include "nodes/types/mesh.h"

namespace scallop::mesh_nodes {

NodeDecl make_denoise_node() {
  const MeshDenoiseOptions def;  // the defaults live in the options
  NodeDecl d;
  d.type = "mesh.denoise";
  d.version = 1;
  d.description =
      "feature-preserving denoising of a triangle mesh: face normals filtered (tgv: MeshTGV, "
      "total generalised variation by the augmented Lagrangian method; bilateral: bilateral "
      "normal filtering), then vertices moved to fit them (parallel)";
  d.input("mesh", "Mesh", "a triangle mesh, no edge with 3 or more faces (mesh.repair)")
      .output("mesh", "Mesh",
              "the same faces, labels and feature edges with the vertices moved (vertex normals "
              "recomputed when the input has them)")
      .output("report", "Report",
              "{method, faces, vertices, iterations (of the normal filter), last_turn_mean_deg "
              "and last_turn_max_deg (tgv: how far the normals turned in the last iteration, "
              "area-weighted mean and largest), cg_steps (tgv), move_mean, move_max (mm), "
              "normal_change_mean_deg (area-weighted), normal_change_max_deg, seconds, "
              "filter_seconds, vertex_seconds}")
      .param_choice("method", "tgv", {"tgv", "bilateral", "none"},
                    "tgv: MeshTGV (Liu et al. 2021), keeps flat faces flat, smooth bends smooth and "
                    "sharp edges sharp; bilateral: bilateral normal filtering (Zheng et al. 2011), "
                    "the baseline; none: the mesh passes unchanged (to compare, or for clean scans)")
      .param_float("alpha1", def.tgv.alpha1, 1e-6, 1e6, "",
                   "tgv: weight of the first-order term (jumps of the normals the gradient field "
                   "does not explain) against fidelity to the input normals; larger removes more "
                   "noise and more small detail")
      .param_float("alpha_ratio", def.tgv.alpha_ratio, 1e-3, 1e3, "",
                   "tgv: alpha0 / alpha1, the second-order term's (variation of the gradient "
                   "field) weight against the first; larger keeps bends as sharp edges, smaller "
                   "lets them round off")
      .param_float("penalty", def.tgv.penalty, 0, 1e6, "",
                   "tgv: r, the augmented Lagrangian penalty on both split variables; 0: 7 alpha1 "
                   "(about the fastest convergence)")
      .param_int("tgv_iterations", def.tgv.iterations, 0, 100000, "",
                 "tgv: augmented Lagrangian iterations at most")
      .param_float("tolerance", def.tgv.tolerance, 0, 180, "deg",
                   "tgv: stop when the normals turned less than this in one iteration "
                   "(area-weighted mean)")
      .param_float("sigma_r", def.bilateral.sigma_r, 1e-3, 10, "",
                   "bilateral: width of the range weight on |n_i - n_j| (0.35: about 20 degrees); "
                   "normals further apart hardly mix")
      .param_float("sigma_s", def.bilateral.sigma_s, 0, 1e6, "mm",
                   "bilateral: width of the spatial weight; 0: the mean distance between the "
                   "centroids of faces sharing an edge")
      .param_int("bilateral_iterations", def.bilateral.iterations, 0, 100000, "",
                 "bilateral: filtering iterations")
      .param_int("vertex_iterations", def.vertex_iterations, 0, 100000, "",
                 "vertex updates towards the filtered normals (Sun et al. 2007), both methods");
  d.run = [](NodeContext& ctx) {
    auto mesh = ctx.input<Mesh>("mesh");
    if (ctx.text("method") == "none") {
      Report report;
      report.data = {{"method", "none"}, {"faces", mesh->num_faces()}, {"vertices", mesh->num_vertices()}};
      ctx.set("report", std::move(report));
      ctx.set_output("mesh", mesh);
      return;
    }
    MeshDenoiseOptions o;
    o.method = ctx.text("method") == "bilateral" ? MeshDenoiseMethod::Bilateral : MeshDenoiseMethod::Tgv;
    o.tgv.alpha1 = ctx.number("alpha1");
    o.tgv.alpha_ratio = ctx.number("alpha_ratio");
    o.tgv.penalty = ctx.number("penalty");
    o.tgv.iterations = static_cast<int>(ctx.integer("tgv_iterations"));
    o.tgv.tolerance = ctx.number("tolerance");
    o.bilateral.sigma_r = ctx.number("sigma_r");
    o.bilateral.sigma_s = ctx.number("sigma_s");
    o.bilateral.iterations = static_cast<int>(ctx.integer("bilateral_iterations"));
    o.vertex_iterations = static_cast<int>(ctx.integer("vertex_iterations"));
    const auto t0 = std::chrono::steady_clock::now();
    MeshDenoiseResult r;
    try {
      r = denoise_mesh(*mesh, o, [&](double f) { ctx.progress(f, "denoising"); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(std::string("mesh.denoise: ") + e.what());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    Report report;
    report.data = {{"method", ctx.text("method")},
                   {"faces", mesh->num_faces()},
                   {"vertices", mesh->num_vertices()},
                   {"iterations", r.iterations},
                   {"last_turn_mean_deg", r.last_turn_mean_deg},
                   {"last_turn_max_deg", r.last_turn_max_deg},
                   {"cg_steps", r.cg_steps},
                   {"move_mean", r.move_mean},
                   {"move_max", r.move_max},
                   {"normal_change_mean_deg", r.normal_change_mean_deg},
                   {"normal_change_max_deg", r.normal_change_max_deg},
                   {"seconds", seconds},
                   {"filter_seconds", r.filter_seconds},
                   {"vertex_seconds", r.vertex_seconds}};
    ctx.set("report", std::move(report));
    ctx.set("mesh", std::move(r.mesh));
  };
  return d;
}

}  // namespace scallop::mesh_nodes
