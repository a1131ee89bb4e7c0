// Is a cloud plausibly in millimetres? scallop reads every coordinate as mm; a file in metres
// (or a corrupt one) otherwise gives a silently wrong program: a 100 mm part in metres is 0.1 mm
// wide, and a 4 mm ball "finishes" it with moves 20 times wider than the part.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "engine/node.h"

namespace scallop {

// Coordinates beyond this (mm, 1000 km) are no part to machine: a damaged file or a wrong scale.
inline constexpr double kMaxCoordinateMm = 1e9;

// P  #P positions (mm), NaN and infinite points allowed (cloud.clean drops those).
// The first finite point with a coordinate beyond +-kMaxCoordinateMm, as a message naming it:
//   "point 3 at (1e+300, 0, 0): coordinates out of range (beyond 1e9 mm); the file is damaged
//    or its scale is wrong"
// or "" when there is none. (Left in, 1e300 overflows every sum downstream and the normals
// report the neighbourhood as "coincident or collinear".)
std::string out_of_range_point(const std::vector<Eigen::Vector3d>& P);

// What the cloud's size says about its units. extent = largest side of the bounding box of the
// finite points; spacing = median distance to the nearest other point (over up to 1000 points;
// above 200 000 points, to the nearest of a random 200 000 of them, times sqrt(200 000 / #P):
// within a factor of about 2 of the whole cloud's, enough to tell units), or 0 without
// `spacing` (a mesh's vertices: a CAD mesh's are as far apart as its faces are
// large, whatever the units).
struct CloudScale {
  std::size_t points = 0;  // finite ones
  double extent = 0, spacing = 0;
};
CloudScale measure_scale(const std::vector<Eigen::Vector3d>& P, bool spacing = true);

// A warning when the cloud does not look like millimetres, else "":
//  - smaller than 1 mm across, or points closer than 0.001 mm (1 um) apart: metres?
//      "the cloud is 0.1 mm across with points 0.0014 mm apart: is it in metres? coordinates
//       are read as mm; set read.scale to 1000"
//  - points more than 100 mm apart: micrometres?  "... set read.scale to 0.001"
// `scale` is the scale already applied (the suggestion multiplies it); `scale_setting` names the
// parameter to set ("read.scale": the node id and its parameter); `noun` what was read ("the
// mesh is 0.1 mm across: ...").
std::string units_warning(const CloudScale& s, double scale, const std::string& scale_setting,
                          const std::string& noun = "cloud");

// What io.read_cloud and io.read_mesh check in the points P (mm) they read from `path`: a
// coordinate beyond 1e9 mm throws InputError "<path>: <out_of_range_point>"; points that do not
// look like millimetres are warned about (units_warning with the node's 'scale' parameter;
// `spacing` and `noun` as measure_scale and units_warning take them).
void check_units(const NodeContext& ctx, const std::string& path, const std::vector<Eigen::Vector3d>& P,
                 bool spacing = true, const std::string& noun = "cloud");

}  // namespace scallop
