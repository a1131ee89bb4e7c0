// The gouge guard's check of a ball (BallClearance) built from a node's inputs: the height field
// of its cloud, the outline of its optional input "loops" and its optional input "band"
// (cloud.surface_band). path.gouge_guard and post.link check balls alike, the rim band beyond
// the outline included (rim_band_width: what the planner's band passes cut by default and the
// certificate counts).
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "engine/node.h"
#include "nodes/cloud/surface_band_input.h"
#include "nodes/geom/height_field_model.h"
#include "nodes/geom/outline.h"
#include "nodes/path/gouge_guard.h"
#include "nodes/path/step_size.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop {

// Holds what the check reads (it keeps references): neither copied nor moved.
struct BallClearanceInputs {
  // cloud  the node's cloud (must outlive this); r  the ball's radius (mm).
  BallClearanceInputs(NodeContext& ctx, const PointCloud& cloud, double r)
      : surface(cloud.points, 20, cloud.has_uncertainty() ? &cloud.uncertainty : nullptr),
        outline(ctx.has_input("loops") ? loop_polygons_xy(*ctx.input<BoundaryLoops>("loops"), cloud.points)
                                       : std::vector<std::vector<Eigen::Vector2d>>{}),
        band_cloud(surface_band_input(ctx, cloud)) {
    if (band_cloud) band.emplace(SurfaceBandView{band_cloud->points, band_cloud->uncertainty});
    // (a spacing wider than the certificate's band: the outermost band pass runs along its edge,
    // and its balls reach past it)
    clearance.emplace(surface, cloud.points, r, outline.empty() ? nullptr : &outline, band ? &*band : nullptr,
                      rim_band_width(surface.spacing()) + surface.spacing());
  }
  BallClearanceInputs(const BallClearanceInputs&) = delete;
  BallClearanceInputs& operator=(const BallClearanceInputs&) = delete;

  HeightFieldModel surface;  // what post.simulate certifies against: 20 neighbours
  Outline outline;
  std::shared_ptr<const PointCloud> band_cloud;
  std::optional<SurfaceBandView> band;
  std::optional<BallClearance> clearance;
};

}  // namespace scallop
