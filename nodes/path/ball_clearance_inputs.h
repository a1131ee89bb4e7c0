// The gouge guard's check of a ball (BallClearance) built from a node's inputs: the height field
// of its cloud, the outline of its optional input "loops", its optional input "band"
// (cloud.surface_band) and its optional input "left_out" (the points cloud.trim_steep did not
// keep, which the ball must not reach either). path.gouge_guard and post.link check balls alike, the rim band beyond
// the outline included (rim_band_width: what the planner's band passes cut by default and the
// certificate counts), and share one check: it is built once per cloud, loops, band and radius.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "engine/node.h"
#include "nodes/geom/height_field_model.h"
#include "nodes/geom/outline.h"
#include "nodes/path/gouge_guard.h"
#include "nodes/types/cloud.h"
#include "nodes/types/param.h"

namespace scallop {

// Holds what the check reads (it keeps references): neither copied nor moved.
struct BallClearanceInputs {
  // cloud  must outlive this; loops, band, left_out  null or the node's inputs (kept); r  the
  // ball's radius (mm).
  BallClearanceInputs(const PointCloud& cloud, std::shared_ptr<const BoundaryLoops> loops,
                      std::shared_ptr<const PointCloud> band, std::shared_ptr<const PointCloud> left_out, double r);
  BallClearanceInputs(const BallClearanceInputs&) = delete;
  BallClearanceInputs& operator=(const BallClearanceInputs&) = delete;

  std::shared_ptr<const HeightFieldModel> surface;  // what post.simulate certifies against (shared)
  std::shared_ptr<const BoundaryLoops> loops;
  Outline outline;
  std::shared_ptr<const PointCloud> band_cloud;
  std::optional<SurfaceBandView> band;
  std::shared_ptr<const PointCloud> left_out;
  std::optional<BallClearance> clearance;
};

// The check for the node's inputs "cloud" (given), "loops", "band" and "left_out" (optional) and radius r,
// made on the first call of a run and shared by the later ones with the same inputs and r (it
// lives as long as the cloud value). Throws NodeError for a band that is not the cloud's.
std::shared_ptr<const BallClearanceInputs> ball_clearance_inputs(NodeContext& ctx, const PointCloud& cloud, double r);

}  // namespace scallop
