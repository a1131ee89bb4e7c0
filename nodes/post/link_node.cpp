#include <memory>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/path/ball_clearance_inputs.h"
#include "nodes/post/link.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"
#include "nodes/types/toolpath.h"

namespace scallop::post_nodes {
NodeDecl make_link_node() {
  NodeDecl d;
  d.type = "post.link";
  d.version = 19;  // 19: of left_out only the points apart from the patch and above it (obstacle_points); 18: optional left_out, points the ball keeps clear of, where the field beyond the patch is not extrapolated (stop 92); 17: a foot in a hole within the rim band is on the surface, as beyond the outer loop (stop 90); 16: a residual within the points' uncertainty floor counts as the height field's misfit (HeightFieldModel, stop 88); 15: the height field's quartic where its quadratic misfits (HeightFieldModel, kQuarticFrom); 14: the ball clearance's ring around a foot point only where the field's uncertainty may grow within a spacing (path.gouge_guard v15); 13: the foot search stops halving at 1e-4 mm (HeightFieldModel::foot_point); 12: the ring around the foot at half a spacing and one (BallClearance); 11: links checked as the gouge guard checks a ball (path.gouge_guard's BallClearance: the band above the cloud's points within reach and around the foot beyond the edge too, not only at the foot; a zig-zag turn at the noisy bowl's rim reached 0.0115 into it), optional band; 10: links cleared by the uncertainty less 0.15 of it (the certificate samples it between the places checked), and everywhere inside the loops' outline when given (gaps between rim points); 9: the model under a link is checked at the foot point HeightFieldModel::foot_point finds (stepping to c - r n alone swung off crests tighter than the ball); 7: down at rapid rate to lead_height above a start, then the plunge (was a plunge from the clearance plane); 8: the rapids stop where a ball of r + lead_height would touch the part; 2: fails where the passes rise more than 10 r + the part's height range above it; 4: the height field's uncertainty counts its fit's misfit; 5: the moves stored without their padding bytes; 6: the height field solved by a fixed-size Cholesky
                  // 3: links checked against the cloud's height field too
  d.description = "joins passes in order: short feed links where the ball stays above the surface, else retract to a clearance plane";
  d.input("path", "Toolpath", "the passes, in cutting order")
      .input("cloud", "Cloud", "the surface, for link safety and the clearance plane (else the passes' contact points)", false)
      .input("loops", "Loops", "optional: the cloud's boundary loops; links are then checked against its height "
             "field everywhere inside their outline, as post.simulate does (in gaps between rim points too)", false)
      .input("band", "Cloud", "optional: cloud.surface_band of 'cloud' (computed here when not given)", false)
      .input("left_out", "Cloud", "optional: points of the part not machined (cloud.trim_steep's left_out: a steep "
             "wall beside the patch, a piece apart); the ball keeps clear of them, and off the patch where they "
             "lie the surface is not extrapolated", false)
      .output("linked", "LinkedPath", "tool-tip moves: rapids, plunges and feeds");
  d.options<LinkOptions>()
      .number("max_link", &LinkOptions::max_link, 0, 1e4, "mm",
              "longest direct feed link; 0: twice the largest stepover")
      .number("safety", &LinkOptions::safety, 0, 1e4, "mm", "clearance plane height above the highest surface point")
      .number("lead_height", &LinkOptions::lead_height, 0, 1e3, "mm",
              "how far the rapids keep off the part (more than the stock left): they stop where a ball of r + this coming down would touch it, at least this above a pass start or end")
      .number("tolerance", &LinkOptions::tolerance, 0, 10, "mm",
              "how much closer than r a link may bring the ball to the surface; 0: max(chord error, 0.001)");
  d.run = [](NodeContext& ctx) {
    auto path = ctx.input<Toolpath>("path");
    std::vector<Eigen::Vector3d> none;
    std::shared_ptr<const PointCloud> cloud;
    if (ctx.has_input("cloud")) cloud = ctx.input<PointCloud>("cloud");
    const LinkOptions o = ctx.options<LinkOptions>();
    try {
      // What the certificate measures against, checked as the gouge guard checks a ball.
      std::shared_ptr<const BallClearanceInputs> check;
      if (cloud && cloud->size() >= 10) check = ball_clearance_inputs(ctx, *cloud, path->tool_radius);
      ctx.set("linked", link_passes(*path, cloud ? cloud->points : none, o, check ? &*check->clearance : nullptr));
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
  };
  return d;
}
}  // namespace scallop::post_nodes
