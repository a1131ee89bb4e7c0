// Ball-end passes kept off a whole part in one clamping (post.setup_programs, rest_passes): the
// part in the machine frame (tool axis +z), ball centre = contact + r normal.
//
// Where the part comes closer than r - tolerance to a ball centre, or lies straight above it (the
// tool comes down along +z: it cannot reach under an overhang, and a centre inside the solid is
// far from its surface), the ball is lifted along +z until clear. A move's nearest approach to the
// part is found exactly (MeshDistance::least_on_segment), and where it is too near (or, checked at
// eighths, a point of it lies under the part) a lifted point is inserted and both halves are
// checked again (6 times at most); a move that still reaches in (a narrow neck above a free
// pocket) has its lower end raised to its upper end's height when it lacks at least their height
// difference, else both ends raised by what it lacks, and a move that is still too near
// after that is not cut: the pass is split there and the pieces' ends trimmed back to balls that
// go straight up clear (splits, dropped). A pass's first and last ball, where the tool comes down
// and goes up along +z, is raised until that vertical keeps the ball as far off the part (an
// overhang beside it, not only above it).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct KeepOffStats {
  std::size_t lifted = 0;   // ball positions (and inserted move middles) lifted
  double lift_max = 0;      // mm
  std::size_t dropped = 0;  // ball positions left out: no clear way to them (the pass split there)
  std::size_t splits = 0;   // passes cut in two there
  std::size_t lowered = 0;  // ball positions lowered onto the part
  double lower_max = 0;     // mm
  std::size_t high = 0;     // planned balls lifted more than the ball's radius
  double high_max = 0;      // mm, the largest such lift
  Eigen::Vector3d high_at = Eigen::Vector3d::Zero();  // its planned contact (machine frame)
};

// The ball centre c lifted along +z until the part is at least r - tolerance from it and nothing
// of the part lies straight above it; returns the lift.
double lift_clear(Eigen::Vector3d& c, const MeshDistance& part, double r, double tolerance);

// The ball centre c lowered along -z, at most max_drop, until it touches the part (r from it):
// where the surface a pass was planned on lies above the part (a smooth B-spline over a faceted
// STL's flat facets, or one that bulges between its quads), the ball comes down onto the part
// instead of leaving that much stock. Exact (MeshDistance::touch_along, one ray); before stop 62
// it stepped by the distance beyond r, 1 - cos(theta) of the gap a step on a slope of theta.
// Returns the drop.
double drop_onto(Eigen::Vector3d& c, const MeshDistance& part, double r, double max_drop);

// One pass kept off the part (see above), each ball first lowered onto the part by at most
// max_drop. part_top_z: the part's highest z. Returns the pass as pieces: split where a move
// could not be kept off the part.
std::vector<ToolpathPass> keep_pass_off_part(ToolpathPass pass, double r, const MeshDistance& part, double part_top_z,
                                             double tolerance, double max_drop, KeepOffStats& stats);

// Every pass of `path` kept off the part, side by side (each on its own: the same result in any
// order); max_drop per pass (missing: 0). The passes are replaced by their pieces.
KeepOffStats keep_off_part(Toolpath& path, const std::vector<double>& max_drop, const MeshDistance& part,
                           double part_top_z, double tolerance);

}  // namespace scallop
