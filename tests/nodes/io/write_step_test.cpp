// io.write_step: fitted patches to STEP and back through OpenCASCADE's reader.
#include "nodes/io/write_step.h"

#include <gtest/gtest.h>

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
  NodeContext ctx(d, "step", "part", {{"path", "out/part.step"}, {"sew", true}, {"sewing_tolerance", 0.01}}, {{"surfaces", s}}, nullptr, {});
  ctx.set_output_dir(dir.str());
  d.run(ctx);
  auto outputs = ctx.take_outputs();
  EXPECT_EQ(std::dynamic_pointer_cast<const FileRef>(outputs.at("file"))->path, (dir.path / "out/part.step").string());
  const auto& r = std::dynamic_pointer_cast<const Report>(outputs.at("report"))->data;
  EXPECT_EQ(r["faces"], 6);
  EXPECT_EQ(r["shells"], 1);

  NodeContext bad(d, "step", "part", {{"path", ""}, {"sew", true}, {"sewing_tolerance", 0.01}}, {{"surfaces", s}}, nullptr, {});
  bad.set_output_dir(dir.str());
  EXPECT_EQ(test::error_of<NodeError>([&] { d.run(bad); }), "parameter 'path' is empty: give the file to write");
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
