// One machine program per clamping (issue 14): the passes of each setup's patches taken into that
// setup's machine frame (tool axis +z), linked and written as G-code, with the setups file that
// ../shared/tools/verify_part.py and a machinist read (format scallop-setups/1).
//
// A part point p is at R p + t in setup s's frame ([R|t] = its part_to_machine), a normal n at
// R n. Where the patch's surface stands above the part (patch_off_part), each ball is first
// lowered along -z until it touches the part. The balls are kept off the whole part, not only off
// the patch they cut (keep_off_part.h), and off the cloud's points where given; the lifts are
// counted (stock left). Links are kept as far
// off the part (checked against its vertices and its faces), and the clearance plane set above
// its points (link.h).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/mesh/self_crossings.h"
#include "nodes/post/gcode.h"
#include "nodes/post/link.h"
#include "nodes/post/rest_passes.h"
#include "nodes/surface/setups.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct SetupProgram {
  std::size_t setup = 0;   // index of its setup
  std::string name;
  std::string file;        // "setup_<k>.ngc", k from 1
  std::string gcode;       // the program text
  LinkedPath linked;       // its moves, machine frame, as the program writes them (4 decimals)
  std::size_t passes = 0;  // contours cut
  std::size_t moves = 0;
  double clearance_z = 0;  // mm, machine frame
  std::size_t lifted = 0;   // ball positions (and inserted move middles) lifted off the part
  double lift_max = 0;      // mm, the largest lift
  std::size_t splits = 0;   // passes cut where a move could not be kept off the part
  std::size_t dropped = 0;  // ball positions left out there (no clear way down or up to them)
  std::size_t lowered = 0;  // ball positions lowered onto the part (patch_off_part)
  double lower_max = 0;     // mm, the largest drop
  // Planned ball positions lifted more than the ball's radius: they touch nothing near where they
  // were planned (from this setup the part is in the way there); the largest such lift and its
  // planned contact in the part's frame.
  std::size_t high_lifts = 0;
  double high_lift_max = 0;
  Eigen::Vector3d high_lift_at = Eigen::Vector3d::Zero();
  std::size_t rest_passes = 0;  // passes added where the others left material (rest_passes.h)
  double rest_length = 0;       // mm, their length
};

// setups        the clampings (plan_setups, or setups_from_report of surface.setups' report)
// path          the passes of every patch, patch by patch (path.contour_grid)
// passes_per_patch  how many of them each patch has, in order (their sum: path.passes.size())
// part          the whole part in its own frame (its mesh; without faces no ball is lifted)
// patch_off_part  per patch, how far its surface lies from the part at most (path.contour_grid's
//               part_distance_max; empty: 0): where the surface stands above the part, a ball is
//               lowered along -z onto it by up to 5 times that (a setup's patch is at most that
//               steep), so that it touches the part and leaves no such stock
// rest          where given (and rest->rounds > 0), what the passes leave over the scallop limit
//               is cut again from the setups that reach it (rest_passes.h; tool, h and e from
//               `path`; places no setup comes down to may get setups of their own, numbered
//               after `setups`: SetupProgram::setup indexes setups then rest_result->added_setups),
//               and rest_result gets what was found
// held_points   points the part holds besides its faces (the cloud the mesh was made from, part
//               frame): the balls, moves and links are kept off them too, and the clearance plane
//               clears them (where the mesh does not hold its cloud, a fold or a filled hole)
// keep_out      where the part's mesh crosses itself (tangle_keep_out of self_crossings(part)): the
//               balls, moves and links are kept its margin farther from its samples
// progress      optional: the fraction done and what is being done (the block's 200 000-point
//               cloud took 230 s here: keeping the passes off the part, rest passes, linking)
// Returns one program per setup that cuts anything (a setup none of whose balls could be kept off
// the part gets none). Throws std::invalid_argument when the counts
// do not add up; link_passes' and write_gcode's errors pass through.
std::vector<SetupProgram> setup_programs(const Toolpath& path, const std::vector<std::size_t>& passes_per_patch,
                                         const std::vector<Setup>& setups, const Mesh& part,
                                         const LinkOptions& link, const GCodeOptions& gcode,
                                         const std::vector<double>& patch_off_part = {},
                                         const RestOptions* rest = nullptr, RestResult* rest_result = nullptr,
                                         const std::vector<Eigen::Vector3d>& held_points = {},
                                         const std::function<void(double, const std::string&)>& progress = {},
                                         const TangleKeepOut& keep_out = {});

// The setups file: {"format": "scallop-setups/1", "units": "mm", "setups": [{name, gcode,
// part_to_machine}]}.
nlohmann::json setups_file(const std::vector<SetupProgram>& programs, const std::vector<Setup>& setups);

}  // namespace scallop
