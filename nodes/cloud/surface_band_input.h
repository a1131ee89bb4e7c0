// The optional input "band" of a node that checks a ball against a cloud's height field
// (path.isoparametric, path.gouge_guard, post.link): cloud.surface_band of that cloud, so the
// field's uncertainty above every point is computed once and cached.
#pragma once

#include <memory>
#include <string>

#include "engine/node.h"
#include "nodes/types/cloud.h"

namespace scallop {

// The node's input "band" when it has one (null otherwise), checked against `cloud`: one place
// with an uncertainty per point. Throws NodeError saying what was given.
inline std::shared_ptr<const PointCloud> surface_band_input(NodeContext& ctx, const PointCloud& cloud) {
  if (!ctx.has_input("band")) return nullptr;
  auto band = ctx.input<PointCloud>("band");
  if (band->size() != cloud.size() || !band->has_uncertainty())
    throw NodeError("the band has " + std::to_string(band->size()) + " places" +
                    (band->has_uncertainty() ? "" : " without uncertainties") + " for a cloud of " +
                    std::to_string(cloud.size()) + " points: give cloud.surface_band of the same cloud");
  return band;
}

}  // namespace scallop
