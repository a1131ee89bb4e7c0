#include "nodes/post/setup_sheet.h"

#include <gtest/gtest.h>

#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// A 20 x 20 x 10 box whose top (patch 0) is cut standing (+z) and whose +x side (patch 1) is cut
// turned onto its -x side.
struct TwoClampings {
  std::vector<Setup> setups;
  SetupPaths programs;
  Mesh surfaces = test::quad_box({2, 2, 2}, V(20, 20, 10));
  TwoClampings() {
    for (std::size_t f = 0; f < surfaces.num_faces(); ++f) {
      const V n = test::cube_side_normal(surfaces.face_label[f]);
      surfaces.face_label[f] = n.z() > 0.5 ? 0 : n.x() > 0.5 ? 1 : -1;
    }
    for (const V& axis : {V(0, 0, 1), V(1, 0, 0)}) {
      Setup& s = setups.emplace_back();
      s.axis = axis;
      s.name = std::to_string(setups.size()) + (axis.z() > 0 ? ": +z" : ": +x");
      s.rotation = rotation_to_z(axis);
      s.translation = V(1, 2, 3);
      s.patches = {std::uint32_t(setups.size() - 1)};
      s.min_normal_dot = 1;
      SetupPath& p = programs.setups.emplace_back();
      p.name = s.name, p.file = "setup_" + std::to_string(setups.size()) + ".ngc";
      p.rotation = s.rotation, p.translation = s.translation;
      p.path.tool_radius = 3, p.path.scallop_height = 0.05, p.path.chord_error = 0.01, p.path.clearance_z = 25;
      p.path.moves = {{MoveKind::Rapid, V(0, 0, 25)},
                      {MoveKind::Rapid, V(0, 0, 11)},
                      {MoveKind::Plunge, V(0, 0, 10)},
                      {MoveKind::Feed, V(40, 0, 10)}};
    }
  }
};

TEST(SetupSheet, SaysHowToClampEachSetupWithAPictureAndTheVerdict) {
  const TwoClampings t;
  const nlohmann::json certificate = {{"pass", false},
                                      {"fail_reasons", {"interior scallop max 0.06 > 1.01 H"}},
                                      {"scallop_max_interior", 0.06},
                                      {"gouge_max", 0.001},
                                      {"base_fraction", 0.2},
                                      {"unreachable_fraction", 0.0},
                                      {"setups", {{{"name", "2: +x"}, {"finished_fraction", 0.25}, {"gouge_max", 0.001}}}}};
  const SetupSheet sheet = setup_sheet(t.programs, t.setups, t.surfaces, &certificate, 300);
  const std::string& md = sheet.markdown;
  for (const char* line :
       {"Tool: ball-end mill, radius 3.000 mm (diameter 6.000 mm)",
        "**Certificate: FAIL — do not cut.** interior scallop max 0.06 > 1.01 H.",
        "| 1 | `setup_1.ngc` | +z | 1 | 4 | 41 | 25.00 |", "| 2 | `setup_2.ngc` | +x | 1 | 4 | 41 | 25.00 |",
        "mm of cut; rapids at Z 25.00, stopping at least 1.00 mm above each pass start (leave less stock than that).",
        "turn the part so that its direction +z points up at the spindle; the side facing -z rests on the table or "
        "fixture (the part as it stands).",
        "turn the part so that its direction +x points up at the spindle; the side facing -x rests on the table or "
        "fixture.",
        "- **Certificate**: this setup leaves the finished surface on 25.0 % of the measured area",
        "![setup 2: the part as clamped"})
    EXPECT_NE(md.find(line), std::string::npos) << line << "\n" << md;
  ASSERT_EQ(sheet.pictures.size(), 2u);
  EXPECT_EQ(sheet.pictures[1].first, "setup_2.png");
  EXPECT_EQ(sheet.pictures[1].second.substr(1, 3), "PNG");
}

TEST(SetupSheet, AProgramForAnUnknownSetupIsNamed) {
  TwoClampings t;
  t.programs.setups[1].name = "7: -y";
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { setup_sheet(t.programs, t.setups, t.surfaces, nullptr); }),
            "program 'setup_2.ngc' is for setup '7: -y', which the setups report does not have");
}

}  // namespace
}  // namespace scallop
