#include "nodes/path/ball_clearance_inputs.h"

#include <cstdio>

#include "nodes/cloud/surface_band_input.h"
#include "nodes/cloud/cloud_height_field.h"
#include "nodes/path/step_size.h"

namespace scallop {

BallClearanceInputs::BallClearanceInputs(const PointCloud& cloud, std::shared_ptr<const BoundaryLoops> loops_in,
                                         std::shared_ptr<const PointCloud> band_in,
                                         std::shared_ptr<const PointCloud> left_out_in, double r)
    : surface(cloud_height_field(cloud)),
      loops(std::move(loops_in)),
      outline(loops ? loop_polygons_xy(*loops, cloud.points) : std::vector<std::vector<Eigen::Vector2d>>{}),
      band_cloud(std::move(band_in)),
      left_out(std::move(left_out_in)) {
  if (band_cloud) band.emplace(SurfaceBandView{band_cloud->points, band_cloud->uncertainty});
  // (a spacing wider than the certificate's band: the outermost band pass runs along its edge,
  // and its balls reach past it)
  clearance.emplace(*surface, cloud.points, r, outline.empty() ? nullptr : &outline, band ? &*band : nullptr,
                    rim_band_width(surface->spacing()) + surface->spacing(),
                    left_out && left_out->size() ? &left_out->points : nullptr);
}

std::shared_ptr<const BallClearanceInputs> ball_clearance_inputs(NodeContext& ctx, const PointCloud& cloud, double r) {
  std::shared_ptr<const BoundaryLoops> loops = ctx.has_input("loops") ? ctx.input<BoundaryLoops>("loops") : nullptr;
  std::shared_ptr<const PointCloud> band = surface_band_input(ctx, cloud);
  std::shared_ptr<const PointCloud> left_out = ctx.has_input("left_out") ? ctx.input<PointCloud>("left_out") : nullptr;
  // The entry keeps loops, band and left_out alive, so their addresses name them for as long as it lives.
  char key[200];
  std::snprintf(key, sizeof key, "ball_clearance/%a/%p/%p/%p", r, static_cast<const void*>(loops.get()),
                static_cast<const void*>(band.get()), static_cast<const void*>(left_out.get()));
  return cloud.derived<BallClearanceInputs>(
      key, [&] { return std::make_shared<const BallClearanceInputs>(cloud, loops, band, left_out, r); });
}

}  // namespace scallop
