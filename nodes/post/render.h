// Pictures of tool paths for people: PNG (libpng) and SVG.
//
// Views: "top" (xy, y up), "iso" (isometric, seen from (−1, −1, 1)), "uv" (the parameter domain,
// when passes carry uv), "scallop" (heat map of a simulation, top view, colour bar 0..1.01 h:
// red above 1.01 h, magenta uncut, black gouged beyond tolerance). Cloud points are drawn shaded
// by height under the paths; feed passes alternate two colours so neighbours can be told apart.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nodes/types/cloud.h"
#include "nodes/types/mesh.h"
#include "nodes/types/simulation.h"
#include "nodes/types/toolpath.h"

namespace scallop {

// An RGB picture, rows top to bottom.
struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // width*height*3
};

// PNG bytes of a picture (8-bit RGB). Throws std::runtime_error if libpng fails.
std::string encode_png(const Picture& picture);

// The passes (and the cloud under them when given, may be null) in view "top", "iso" or "uv",
// `width` pixels wide (height from the aspect). Throws std::invalid_argument for an unknown view,
// an empty path, or "uv" when no pass carries uv.
Picture render_path(const Toolpath& path, const PointCloud* cloud, const std::string& view, int width);
std::string render_path_svg(const Toolpath& path, const PointCloud* cloud, const std::string& view, int width);

// Scallop heat map of a simulation (top view) with a labelled colour bar, coloured against the
// simulation's own limits (scallop_limit, gouge_tolerance). Throws std::invalid_argument for a
// simulation without samples or limit, or width < 142 px.
Picture render_scallop(const Simulation& sim, int width);
std::string render_scallop_png(const Simulation& sim, int width);
std::string render_scallop_svg(const Simulation& sim, int width);

// A whole part's simulation (post.simulate_part) on its mesh, seen from (-1, -1, 1) and from
// (1, 1, 1) side by side, each face coloured by its worst sample as render_scallop colours them
// (light grey: nothing measured there, on the table or unreachable), with the colour bar.
// Throws std::invalid_argument for a simulation without faces, a face the mesh lacks, or width <
// 238 px.
Picture render_part_scallop(const Mesh& mesh, const Simulation& sim, int width);

}  // namespace scallop
