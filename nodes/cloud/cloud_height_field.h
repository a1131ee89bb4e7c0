// The height field of a cloud value, built once per value and shared by every node that reads
// that cloud: the surface band, planner, gouge guard, link and certificate each built their own
// before (a grid and a k-d tree over the whole cloud each time; at a million points about half a
// second apiece, mostly on one thread).
#pragma once

#include <memory>

#include "nodes/geom/height_field_model.h"
#include "nodes/types/cloud.h"

namespace scallop {

// HeightFieldModel over cloud.points with 20 neighbours and the points' uncertainty when the
// cloud has one (what post.simulate certifies against). It reads the cloud in place: keep the
// cloud value alive while using it. Throws std::invalid_argument as HeightFieldModel does.
std::shared_ptr<const HeightFieldModel> cloud_height_field(const PointCloud& cloud);

}  // namespace scallop
