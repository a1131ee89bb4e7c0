// Tests for write_ply and the io.write_cloud node.
#include "nodes/types/ply_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/read_cloud.h"

namespace scallop {
namespace io_nodes {
NodeDecl make_write_cloud_node();
}  // namespace io_nodes
using io_nodes::make_write_cloud_node;
}

namespace scallop {
namespace {

namespace fs = std::filesystem;
using V = Eigen::Vector3d;

class WriteCloud : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() / ("scallop_io_write_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string slurp(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }
  fs::path dir_;
};

PointCloud two_points(bool normals) {
  PointCloud c;
  c.points = {V(0.1, -2, 3e10), V(std::numeric_limits<double>::quiet_NaN(), 0, -0.0)};
  if (normals) c.normals = {V(0, 0, 1), V(1, 0, 0)};
  return c;
}

TEST_F(WriteCloud, AsciiTextIsExactShortestForm) {
  write_ply(path("a.ply"), two_points(true), false);
  EXPECT_EQ(slurp(path("a.ply")),
            "ply\nformat ascii 1.0\ncomment written by scallop\nelement vertex 2\n"
            "property double x\nproperty double y\nproperty double z\n"
            "property double nx\nproperty double ny\nproperty double nz\nend_header\n"
            "0.1 -2 3e+10 0 0 1\nnan 0 -0 1 0 0\n");
}

TEST_F(WriteCloud, UncertaintyIsAnExtraPropertyThatReadsBack) {
  PointCloud c = two_points(false);
  c.points[1].x() = 1;
  c.uncertainty = {0.004, 0.25};
  write_ply(path("u.ply"), c, false);
  EXPECT_EQ(slurp(path("u.ply")),
            "ply\nformat ascii 1.0\ncomment written by scallop\nelement vertex 2\n"
            "property double x\nproperty double y\nproperty double z\n"
            "property double uncertainty\nend_header\n"
            "0.1 -2 3e+10 0.004\n1 0 -0 0.25\n");
  write_ply(path("u_bin.ply"), c, true);
  const auto back = read_cloud(path("u_bin.ply"));
  EXPECT_EQ(back.points, c.points);  // the extra property does not disturb the positions
}

TEST_F(WriteCloud, BinaryIsLittleEndianDoubles) {
  const PointCloud c = two_points(false);
  write_ply(path("b.ply"), c);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment written by scallop\nelement vertex 2\n"
      "property double x\nproperty double y\nproperty double z\nend_header\n";
  const std::string s = slurp(path("b.ply"));
  ASSERT_EQ(s.size(), header.size() + 2 * 3 * 8);
  EXPECT_EQ(s.substr(0, header.size()), header);
  double first;
  std::memcpy(&first, s.data() + header.size(), 8);  // this test assumes a little-endian machine
  EXPECT_EQ(first, 0.1);
  const PointCloud r = read_cloud(path("b.ply"));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r.points[0], c.points[0]);
  EXPECT_TRUE(std::isnan(r.points[1][0]));
  EXPECT_TRUE(std::signbit(r.points[1][2]));
}

TEST_F(WriteCloud, WriteFileOfTheValueWritesBinaryPly) {
  two_points(true).write_file(path("v.ply"));
  const PointCloud r = read_cloud(path("v.ply"));
  EXPECT_EQ(r.size(), 2u);
  EXPECT_TRUE(r.has_normals());
}

TEST_F(WriteCloud, Errors) {
  const std::string bad = path("no/such/dir/x.ply");
  try {
    write_ply(bad, two_points(false));
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write '" + bad + "': No such file or directory");
  }
  PointCloud c = two_points(true);
  c.normals.pop_back();
  try {
    write_ply(path("n.ply"), c);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write '" + path("n.ply") + "': the cloud has 1 normals for 2 points");
  }
  EXPECT_FALSE(fs::exists(path("n.ply")));
}

// Runs the io.write_cloud node on `cloud` with `params` and output folder `out_dir`; returns its
// File output.
std::shared_ptr<const FileRef> run_node(const PointCloud& cloud, const nlohmann::json& params,
                                        const std::string& out_dir) {
  const NodeDecl d = make_write_cloud_node();
  NodeContext ctx(d, "write", "part", params, {{"cloud", std::make_shared<PointCloud>(cloud)}}, nullptr);
  ctx.set_output_dir(out_dir);
  d.run(ctx);
  return std::dynamic_pointer_cast<const FileRef>(ctx.take_outputs().at("file"));
}

TEST_F(WriteCloud, NodeDeclaration) {
  const NodeDecl d = make_write_cloud_node();
  EXPECT_EQ(d.type, "io.write_cloud");
  ASSERT_NE(d.find_input("cloud"), nullptr);
  EXPECT_EQ(d.find_input("cloud")->type, "Cloud");
  ASSERT_NE(d.find_output("file"), nullptr);
  EXPECT_EQ(d.find_output("file")->type, "File");
  ASSERT_NE(d.find_param("path"), nullptr);
  EXPECT_EQ(d.find_param("path")->kind, ParamKind::String);
  ASSERT_NE(d.find_param("binary"), nullptr);
  EXPECT_EQ(d.find_param("binary")->default_value, true);
}

TEST_F(WriteCloud, NodeWritesAndReturnsTheFile) {
  const PointCloud c = two_points(true);
  auto f = run_node(c, {{"path", "out.ply"}, {"binary", false}}, dir_.string());
  ASSERT_TRUE(f);
  EXPECT_EQ(f->path, path("out.ply"));
  EXPECT_EQ(f->content_hash.size(), 32u);
  EXPECT_EQ(slurp(path("out.ply")).substr(0, 21), "ply\nformat ascii 1.0\n");
  const PointCloud r = read_cloud(f->path);
  EXPECT_EQ(r.points[0], c.points[0]);
  EXPECT_EQ(r.normals[1], c.normals[1]);
  // Same cloud, binary: a different file, so a different content hash.
  auto g = run_node(c, {{"path", "out.ply"}, {"binary", true}}, dir_.string());
  // a relative path with folders: they are made inside the output folder
  auto h = run_node(c, {{"path", "sub/dir/out.ply"}, {"binary", true}}, dir_.string());
  EXPECT_EQ(h->path, path("sub/dir/out.ply"));
  EXPECT_EQ(h->content_hash, g->content_hash);
  EXPECT_NE(g->content_hash, f->content_hash);
}

TEST_F(WriteCloud, NodeErrors) {
  try {
    run_node(two_points(false), {{"path", ""}, {"binary", true}}, dir_.string());
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'path' is empty: give the file to write");
  }
  // a file where a folder should be
  std::ofstream(path("file")) << "x";
  try {
    run_node(two_points(false), {{"path", "file/x.ply"}, {"binary", true}}, dir_.string());
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot create folder '" + path("file") + "': Not a directory");
  }
  // paths that would leave the output folder (issue 11): refused, nothing written
  fs::create_directories(path("out"));
  for (const auto& [bad, why] :
       {std::pair<std::string, std::string>{"../x.ply", "'../x.ply' would be written outside the output folder"},
        {"a/../../x.ply", "'a/../../x.ply' would be written outside the output folder"},
        {path("abs.ply"), "'" + path("abs.ply") + "' is absolute: it would be written outside the output folder"},
        {".", "'.' names the output folder itself, not a file in it"}}) {
    try {
      run_node(two_points(false), {{"path", bad}, {"binary", true}}, path("out"));
      ADD_FAILURE() << "no error for " << bad;
    } catch (const NodeError& e) {
      EXPECT_EQ(std::string(e.what()), "parameter 'path': " + why + "; expected a relative path inside it, without '..'");
    }
  }
  EXPECT_FALSE(fs::exists(path("x.ply")));
  EXPECT_FALSE(fs::exists(path("abs.ply")));
}

}  // namespace
}  // namespace scallop
