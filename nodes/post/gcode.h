// G-code writer: a LinkedPath (tool-tip moves) as a program in one of three dialects.
//
// XYZ are the ball-end tool TIP (lowest point of the ball), millimetres (G21), absolute (G90),
// 4 decimals. Rapid moves are G0, feed moves G1 at `feed`, plunges G1 at `plunge_feed` (mm/min).
// Optionally, runs of feed points that lie on a circular arc in a plane parallel to XY, XZ or YZ
// are written as one G2/G3 (G17/G18/G19) whose deviation from the polyline it replaces is at most
// `arc_tolerance`.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/types/toolpath.h"

namespace scallop {

struct GCodeOptions {
  std::string dialect = "linuxcnc";  // "linuxcnc" (M2), "grbl" (M2, no % or O-number), "fanuc" (%, O, M30)
  double feed = 1000;                // mm/min, feed moves
  double plunge_feed = 300;          // mm/min, plunges
  double spindle_rpm = 10000;        // M3 S.. at the start and M5 at the end; 0: no spindle words
  bool arcs = false;                 // fit G2/G3 arcs to runs of feed points
  double arc_tolerance = 0;          // mm; <= 0: the path's chord error (at least 1 µm)
  int program_number = 1000;         // fanuc O-number
  std::string graph_name;            // written in the header comment
  std::string input_hash;            // written in the header comment
};

// The whole program text. Throws std::invalid_argument on an unknown dialect, a non-finite
// coordinate, or non-positive feeds.
std::string write_gcode(const LinkedPath& path, const GCodeOptions& options);

// A tool tip as write_gcode writes it (each coordinate to 4 decimals): what the machine, and so
// the certificate, sees.
Eigen::Vector3d as_written(const Eigen::Vector3d& tip);

// One piece of an arc-fitted polyline: either a straight segment to point `end`, or an arc to
// `end` around `centre` in the plane whose normal axis is `axis` (0: YZ/G19, 1: XZ/G18, 2: XY/G17),
// counter-clockwise seen from the + side of that axis when `ccw`.
struct ArcPiece {
  bool arc = false;
  int axis = 2;
  bool ccw = true;
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int first = 0, last = 0;  // indices of the polyline points the piece spans
};

// Splits the polyline P (#P points, mm) into straight segments and arcs. A run of at least 4
// points becomes an arc when all its points share the coordinate along one axis (within 1e-9 mm)
// and every point of the arc is within `tolerance` of the polyline and vice versa. Arcs sweep at
// most 180 degrees and have radius at most `max_radius`. Returns pieces covering P[0]..P[#P-1]
// in order (P[0] itself is the start, not a piece).
std::vector<ArcPiece> fit_arcs(const std::vector<Eigen::Vector3d>& P, double tolerance,
                               double max_radius = 1000.0);

// Points along an arc piece starting at `start`, spaced so the chord error is at most `sagitta`
// (end included, start excluded). For tests and previews.
std::vector<Eigen::Vector3d> arc_points(const Eigen::Vector3d& start, const ArcPiece& piece,
                                        double sagitta);

}  // namespace scallop
