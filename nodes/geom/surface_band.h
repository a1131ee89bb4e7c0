// The band a ball must clear over a cloud's surface, sampled above each of the cloud's points:
// the height field there (HeightFieldModel, what post.simulate certifies against) and how far it
// may be off the real surface (its uncertainty: the points' own and 3 times the fit's misfit).
// path.gouge_guard checks every ball against the samples within its reach, so that a place the
// fit knows poorly (a crest's flattened top) is cleared by its uncertainty even where the ball's
// nearest point lies elsewhere. It does not depend on the tool or the limits: computed once per
// cloud (the node cloud.surface_band), it is cached across runs that change them.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/geom/height_field_model.h"

namespace scallop {

struct SurfaceBand {
  std::vector<Eigen::Vector3d> at;  // #P: the height field above point i (its own z where the
                                    // field does not reach: outside the patch's fit, at a rim)
  std::vector<double> uncertainty;  // #P: how far the field may be off there (mm), >= 0
};

// The same held elsewhere (a cached cloud's points and uncertainties), read in place.
struct SurfaceBandView {
  const std::vector<Eigen::Vector3d>& at;
  const std::vector<double>& uncertainty;
};

// points  #P by 3, the cloud `surface` was fitted to (or any places over it). In parallel.
SurfaceBand surface_band(const HeightFieldModel& surface, const std::vector<Eigen::Vector3d>& points);

}  // namespace scallop
