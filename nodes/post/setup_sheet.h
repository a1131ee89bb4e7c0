// The setup sheet a machinist reads before cutting a part in several clampings (issue 14): the
// setups in order, for each how to clamp the part (which direction points up at the spindle,
// which side rests on the table), where work zero is, the program to load, what it cuts and a
// picture of the part as it stands in that clamping with the faces that setup cuts coloured.
// Markdown, so it reads as text and renders with its pictures in any viewer.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "nodes/surface/setups.h"
#include "nodes/types/mesh.h"
#include "nodes/types/toolpath.h"

namespace scallop {

struct SetupSheet {
  std::string markdown;                                      // setup_sheet.md
  std::vector<std::pair<std::string, std::string>> pictures;  // (file name "setup_<k>.png", PNG bytes)
};

// programs     the programs in cutting order (post.setup_programs), each with its part_to_machine
// setups       the clampings they came from (surface.setups), matched by name: their axes and patches
// surfaces     the patches' surfaces as a mesh, face label = patch (surface.fit_bspline); may have
//              no faces (no pictures then)
// certificate  post.simulate_part's report, or null: its verdict heads the sheet, its per setup
//              figures go with each setup
// Throws std::invalid_argument when a program's setup is not among `setups`.
SetupSheet setup_sheet(const SetupPaths& programs, const std::vector<Setup>& setups, const Mesh& surfaces,
                       const nlohmann::json* certificate, int picture_width = 800);

}  // namespace scallop
