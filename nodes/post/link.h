// Linking: passes in the order given joined into one machine program (tool-tip moves).
//
// Consecutive passes are joined by a straight feed move between their ball centres when that is
// safe: the link is at most `max_link` long and no surface point within r (in xy) of it comes
// closer than r − tolerance to the segment between the two ball centres (the ball never dips into
// the surface). Otherwise the tool lifts, rises to the clearance plane (the
// highest surface point + `safety`, so rapids there never touch the part), travels, and comes
// down: at rapid rate to where a ball of r + `lead_height` coming down that column would touch the
// part (at least `lead_height` above the next start: higher on a slope or beside a wall), then
// plunges at plunge rate. Lifts feed up to that height above a pass end before the rapid: rapids
// keep `lead_height` off the part.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nodes/types/toolpath.h"

namespace scallop {

class BallClearance;  // nodes/path/gouge_guard.h

struct LinkOptions {
  double max_link = 0;     // mm; <= 0: twice the largest stepover between consecutive passes
  double safety = 5;       // mm above the highest surface point: the clearance plane
  double lead_height = 1;  // mm the rapids keep off the part (more than the stock left on it): at
                           // least this above a pass start and end
  double tolerance = 0;    // mm the ball may come closer than r to the surface on a link; <= 0:
                           // max(path chord error, 0.001) (what a simulation lets pass as gouge)
  // Optional: the check that a straight link of the ball centre from a to b is clear of a whole
  // part (its mesh, post.setup_programs), in place of the surface points' (which miss a dip
  // between them): it must hold them, i.e. refuse a link any of them is nearer than r - tolerance to.
  std::function<bool(const Eigen::Vector3d& a, const Eigen::Vector3d& b)> link_clear;
  // Optional: how far a ball of `radius` centred at c moves down (-z) before it touches the part,
  // at most `max` (MeshDistance::touch_along), in place of the surface points' (where the rapids
  // down to a pass start stop).
  std::function<double(const Eigen::Vector3d& c, double radius, double max)> drop;
};

// surface  #S by 3 points of the surface (the cloud); when empty the passes' own contact points
// stand for it.
// clearance  optional: the gouge guard's check of a ball against the cloud's height field with
//          its uncertainty (post.simulate's surface; BallClearance, path/gouge_guard.h: at the
//          foot point, above the cloud's points within reach, around the foot beyond the cloud's
//          edge, inside the outline when it has one). A link is then also checked with it, the ball every
//          quarter of the cloud spacing along it: between sparse points the ball could dip into
//          the surface unseen (measured: 0.015 mm on a 5000-point dome, a link along a hole's
//          edge) and the certificate would fail. The ball may reach into the band by the
//          tolerance less 0.15 u (the certificate samples the uncertainty u between these
//          places, where it is rough: kUncertaintyRoughness, step_size.h); checked at the foot
//          alone, a zig-zag turn at the noisy bowl's rim reached 0.0115 into it.
// Throws std::invalid_argument for r <= 0, no pass with points, a pass whose normals do not match
// its points, or non-finite coordinates, and std::runtime_error (saying where) when a pass rises
// more than 10 r + the surface's height range above the surface's highest point.
LinkedPath link_passes(const Toolpath& path, const std::vector<Eigen::Vector3d>& surface,
                       const LinkOptions& options, const BallClearance* clearance = nullptr);

// Largest distance between consecutive passes: for each pair, the distance from the middle point
// of the later pass to the nearest contact point of the earlier one (mm); 0 for a single pass.
double largest_stepover(const Toolpath& path);

}  // namespace scallop
