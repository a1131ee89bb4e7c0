// Patches with known answers for the surface and path tests.
#pragma once

#include <Eigen/Core>

#include "nodes/types/surfaces.h"

namespace scallop::test {

// The flat (bilinear) patch with corners p00 (u = v = 0), p10 (u = 1), p01 (v = 1), p11,
// machined along `direction` (normalised).
inline SurfacePatch flat_patch(const Eigen::Vector3d& p00, const Eigen::Vector3d& p10, const Eigen::Vector3d& p01,
                               const Eigen::Vector3d& p11, const Eigen::Vector3d& direction) {
  SurfacePatch p;
  p.surface.degree_u = p.surface.degree_v = 1;
  p.surface.knots_u = p.surface.knots_v = {0, 0, 1, 1};
  p.surface.poles_u = p.surface.poles_v = 2;
  p.surface.poles = {p00, p10, p01, p11};
  p.direction = direction.normalized();
  return p;
}

}  // namespace scallop::test
