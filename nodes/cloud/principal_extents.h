// How long, wide and thick a cloud is along its own principal directions.
//
// A cloud that is a line (a scan of an edge, a line with micron jitter) is no surface to
// machine. Left to run, it gets normals of arbitrary tilt around the line, "walls" and a (u,v)
// map that folds everywhere, and the user is told about those instead of what is wrong.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

struct PrincipalExtents {
  double length = 0, width = 0, thickness = 0;  // mm, along the principal axes, largest first
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // the direction of `length`, unit
};

// P  #P positions (mm), finite. Principal axes of the covariance of P; each extent is the range
// of the points' projections on its axis (all 0 for fewer than 2 points).
PrincipalExtents principal_extents(const std::vector<Eigen::Vector3d>& P);

// Whether the cloud is one-dimensional for a point spacing `spacing` (mm): narrower than one
// spacing, or than 1/1000 of its length: a single row of points, up to noise. (A curved row, a
// profile bent in a plane, is wider than that and not caught here.)
bool one_dimensional(const PrincipalExtents& e, double spacing);

// The median distance from a point to its nearest neighbour at a positive distance (exact
// duplicates skipped), over the points of `nbrs` that have one; 0 when none has.
double median_spacing(const Neighborhoods& nbrs);

// The refusal of a one-dimensional cloud, or "": "the cloud is one-dimensional: its points lie
// along a line 50 mm long and 0.006 mm wide (points 0.0167 mm apart), not on a surface; scallop
// machines surface patches". The first node that looks at the cloud's shape says it, before
// normals of arbitrary tilt around the line make it look steep or folded.
std::string one_dimensional_problem(const PrincipalExtents& e, double spacing);

}  // namespace scallop
