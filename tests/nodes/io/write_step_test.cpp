// io.write_step: fitted patches to STEP and back through OpenCASCADE's reader.
#include "nodes/io/write_step.h"

#include <gtest/gtest.h>

#include <sstream>

#include "engine/file_ref.h"
#include "nodes/all_nodes.h"
#include "nodes/mesh/segment.h"
#include "nodes/surface/fit_bspline.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

Surfaces cylinder_surfaces() {
  SegmentOptions so;
  so.join = false;
  return fit_surfaces(segment_shf(test::capped_cylinder(6), so), FitBSplineOptions{});
}

// The six patches of a closed cylinder, sewn along their shared borders: one closed shell.
TEST(WriteStep, AClosedCylindersPatchesReadBackAsOneClosedShell) {
  test::TempDir dir;
  const Surfaces s = cylinder_surfaces();
  const std::string path = (dir.path / "cyl.step").string();
  write_step(s, path, WriteStepOptions{});
  const StepSummary back = read_step_summary(path);
  EXPECT_EQ(back.file_faces, 6u);
  EXPECT_EQ(back.faces, 6u);
  EXPECT_EQ(back.bspline_faces, 6u);
  EXPECT_EQ(back.shells, 1u);
  EXPECT_EQ(back.free_edges, 0u);
  EXPECT_NE(test::read_file(path).find("ISO-10303-21"), std::string::npos);

  WriteStepOptions loose;
  loose.sew = false;
  write_step(s, path, loose);
  const StepSummary apart = read_step_summary(path);
  EXPECT_EQ(apart.faces, 6u);
  EXPECT_EQ(apart.free_edges, 24u);  // four borders a face, none shared
}

TEST(WriteStep, NodeWritesInsideTheOutputFolderAndReportsWhatReadsBack) {
  test::TempDir dir;
  const NodeDecl& d = *builtin_registry().find("io.write_step");
  EXPECT_FALSE(d.cache_on_disk);
  auto s = std::make_shared<Surfaces>(cylinder_surfaces());
  std::vector<std::string> warnings;
  NodeContext ctx(d, "step", "part", {{"path", "out/part.step"}, {"sew", true}, {"sewing_tolerance", 0.01}}, {{"surfaces", s}}, nullptr,
                  [&](const std::string& m) { warnings.push_back(m); });
  ctx.set_output_dir(dir.str());
  d.run(ctx);
  auto outputs = ctx.take_outputs();
  EXPECT_EQ(std::dynamic_pointer_cast<const FileRef>(outputs.at("file"))->path, (dir.path / "out/part.step").string());
  const auto& r = std::dynamic_pointer_cast<const Report>(outputs.at("report"))->data;
  EXPECT_EQ(r["file_faces"], 6);
  EXPECT_EQ(r["faces"], 6);
  EXPECT_EQ(r["shells"], 1);
  EXPECT_TRUE(warnings.empty());

  NodeContext bad(d, "step", "part", {{"path", ""}, {"sew", true}, {"sewing_tolerance", 0.01}}, {{"surfaces", s}}, nullptr, {});
  bad.set_output_dir(dir.str());
  EXPECT_EQ(test::error_of<NodeError>([&] { d.run(bad); }), "parameter 'path' is empty: give the file to write");
}

// Reads patches written as tests/data/fandisk_noisy_sliver.txt is.
Surfaces read_patches(const std::string& path) {
  std::istringstream in([&] {
    std::string text, line;
    std::istringstream all(test::read_file(path));
    while (std::getline(all, line))
      if (line.empty() || line[0] != '#') text += line + "\n";
    return text;
  }());
  Surfaces s;
  SurfacePatch p;
  while (in >> p.surface.degree_u >> p.surface.degree_v >> p.surface.poles_u >> p.surface.poles_v) {
    p.surface.knots_u.assign(p.surface.poles_u + p.surface.degree_u + 1, 0);
    p.surface.knots_v.assign(p.surface.poles_v + p.surface.degree_v + 1, 0);
    p.surface.poles.assign(std::size_t(p.surface.poles_u) * p.surface.poles_v, Eigen::Vector3d::Zero());
    for (double& k : p.surface.knots_u) in >> k;
    for (double& k : p.surface.knots_v) in >> k;
    for (Eigen::Vector3d& q : p.surface.poles) in >> q.x() >> q.y() >> q.z();
    s.patches.push_back(p);
  }
  return s;
}

// Two patches of the fandisk x 50's noisy cloud: a 2 x 19-pole sliver whose borders cross near its
// tip, and the patch beside it. Sewn, OpenCASCADE's reader heals the sliver into three faces, and
// the node's check (faces read back = patches) failed the whole run. The file holds one face a
// patch; the node checks that, and says what the reader makes of it.
TEST(WriteStep, APatchTheReaderSplitsIsStillOneFaceInTheFile) {
  test::TempDir dir;
  auto s = std::make_shared<Surfaces>(read_patches(std::string(SCALLOP_SOURCE_DIR) + "/tests/data/fandisk_noisy_sliver.txt"));
  ASSERT_EQ(s->patches.size(), 2u);
  const std::string path = (dir.path / "sliver.step").string();
  write_step(*s, path, WriteStepOptions{});
  const StepSummary back = read_step_summary(path);
  EXPECT_EQ(back.file_faces, 2u);
  EXPECT_GT(back.faces, 2u);

  const NodeDecl& d = *builtin_registry().find("io.write_step");
  std::vector<std::string> warnings;
  NodeContext ctx(d, "step", "part", {{"path", "sliver.step"}, {"sew", true}, {"sewing_tolerance", 0.01}}, {{"surfaces", s}}, nullptr,
                  [&](const std::string& m) { warnings.push_back(m); });
  ctx.set_output_dir(dir.str());
  d.run(ctx);
  const auto outputs = ctx.take_outputs();
  const auto& r = std::dynamic_pointer_cast<const Report>(outputs.at("report"))->data;
  EXPECT_EQ(r["file_faces"], 2);
  EXPECT_EQ(r["faces"], back.faces);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "OpenCASCADE's reader splits the file's 2 faces into " + std::to_string(back.faces) +
                                   " (its shape healing cuts a patch that pinches or twists); the file holds one "
                                   "face per patch");
}

TEST(WriteStep, ABrokenSurfaceIsNamed) {
  test::TempDir dir;
  Surfaces s = cylinder_surfaces();
  s.patches[3].surface.poles.pop_back();
  EXPECT_EQ(test::error_of<std::runtime_error>([&] { write_step(s, (dir.path / "x.step").string(), WriteStepOptions{}); }),
            "patch 3: " + std::to_string(s.patches[3].surface.poles.size()) + " poles for a " +
                std::to_string(s.patches[3].surface.poles_u) + " by " + std::to_string(s.patches[3].surface.poles_v) +
                " net");
}

}  // namespace
}  // namespace scallop
