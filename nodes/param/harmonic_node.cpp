#include <stdexcept>

#include "engine/node.h"
#include "nodes/param/boundary_map.h"
#include "nodes/param/harmonic.h"
#include "nodes/param/laplacian.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop::param_nodes {

NodeDecl make_harmonic_node() {
  NodeDecl d;
  d.type = "param.harmonic";
  d.version = 6;  // 6: rows no neighbour leads out of joined both ways instead of an error; 4: the band depth measured on a first map solved to 1e-9 (from 50 000 unknowns); 5: two-level preconditioner coarse first, the band depth to 1e-8, the map to 1e-10
  d.description = "harmonic (conformal) map: L u = L v = 0 inside, outer boundary band fixed, holes free";
  d.input("laplacian", "Laplacian", "the meshless Laplacian of the cloud")
      .input("map", "UVMap", "the boundary map (param.boundary_map)")
      .input("loops", "Loops", "the boundary loops the map was made from")
      .input("cloud", "Cloud", "the points")
      .output("map", "UVMap", "the map with uv of every point and the solve's relative residual")
      .param_choice("solver", "two_level", {"two_level", "direct", "bicgstab", "gmres"},
                    "two_level: from 50 000 points, GMRES preconditioned by Gauss-Seidel and a direct solve on "
                    "aggregates of neighbours, relative residual 1e-11 (direct below, or when it does not "
                    "converge); direct: UMFPACK "
                    "sparse LU of the whole system; bicgstab / gmres: Eigen iterative with incomplete LU")
      .param_bool("fix_band", true,
                  "fix the whole outer boundary band at its projection on the smoothed loop and its depth "
                  "inside it, scaled like the map (else only the loop points, on the domain's edge)");
  d.run = [](NodeContext& ctx) {
    auto lap = ctx.input<Laplacian>("laplacian");
    auto bmap = ctx.input<UVMap>("map");
    auto loops = ctx.input<BoundaryLoops>("loops");
    auto cloud = ctx.input<PointCloud>("cloud");
    if (static_cast<std::size_t>(lap->L.rows()) != cloud->size())
      throw NodeError("the Laplacian has " + std::to_string(lap->L.rows()) + " rows but the cloud has " +
                      std::to_string(cloud->size()) + " points");
    if (loops->loops.empty() || loops->loops[0] != bmap->outer_loop)
      throw NodeError("the boundary map was not made from the outer loop of these loops");
    try {
      const HarmonicSolver solver = parse_harmonic_solver(ctx.text("solver"));
      // Rows that lead nowhere (a denser region beside a sparser one) are rebuilt over their
      // neighbours both ways, with the Laplacian's own scheme.
      std::size_t joined = 0;
      const JoinRows join = [&](const std::vector<int>& points) {
        joined = points.size();
        return join_rows_both_ways(lap->L, cloud->points, cloud->normals, parse_laplacian_scheme(lap->scheme),
                                   lap->heat_time, lap->regularization, points);
      };
      if (ctx.flag("fix_band"))
        ctx.set("map", solve_harmonic_band(lap->L, cloud->points, cloud->normals, loops->is_boundary, loops->loops,
                                           *bmap, solver,
                                           [&ctx](double f, const std::string& m) { ctx.progress(f, m); }, join));
      else {
        ctx.progress(0.05, "solving for " + std::to_string(lap->L.rows()) + " points");
        ctx.set("map", solve_harmonic(lap->L, *bmap, solver, {}, join));
      }
      if (joined > 0)
        ctx.warn(std::to_string(joined) + " points had their nearest neighbours all among themselves (a denser region "
                 "beside a sparser one), so no row led from them to the boundary: their rows were rebuilt over their "
                 "neighbours both ways, the points they name and those naming them");
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    } catch (const std::runtime_error& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}

}  // namespace scallop::param_nodes
