// Tests for write_mesh (PLY, OFF, OBJ, STL) and the io.write_mesh node: exact files and round
// trips through read_mesh for every format.
#include "nodes/io/write_mesh.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/read_mesh.h"
#include "nodes/types/ply_writer.h"
#include "tests/nodes/io/bytes.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace io_nodes {
NodeDecl make_write_mesh_node();
}  // namespace io_nodes
using io_nodes::make_write_mesh_node;
}  // namespace scallop

namespace scallop {
namespace {

using test::corners;
using V = Eigen::Vector3d;

class WriteMesh : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (dir_.path / name).string(); }
  test::TempDir dir_;
};

// The cube with everything a Mesh can carry, and coordinates no decimal form of fewer than 17
// digits gives back.
Mesh full_cube() {
  Mesh m = test::unit_cube();
  m.vertices[1].x() = 0.1;
  m.vertices[7] = V(std::numbers::pi, 1e-300, 123456789.123456789);
  for (const V& v : m.vertices) m.normals.push_back((v - V(0.5, 0.5, 0.5)).normalized());
  m.face_label = {0, 1, 2, 3, -1, 5};
  m.feature_edges = {{{0, 1}}, {{3, 7}}};
  return m;
}

void expect_same_faces(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.face_start, b.face_start);
  EXPECT_EQ(a.face_vertices, b.face_vertices);
}

TEST_F(WriteMesh, PlyRoundTripKeepsEverything) {
  const Mesh m = full_cube();
  write_mesh(m, path("c.ply"), "ply");
  const Mesh r = read_mesh(path("c.ply"));
  EXPECT_EQ(r.vertices, m.vertices);
  expect_same_faces(r, m);
  EXPECT_EQ(r.normals, m.normals);
  EXPECT_EQ(r.face_label, m.face_label);
  EXPECT_EQ(r.feature_edges, m.feature_edges);
  // the Mesh's own file form, byte for byte
  m.write_file(path("own.ply"));
  EXPECT_EQ(test::read_file(path("c.ply")), test::read_file(path("own.ply")));
}

TEST_F(WriteMesh, OffAndObjAreExactText) {
  const Mesh t = test::tetrahedron();
  write_mesh(t, path("t.off"), "off");
  EXPECT_EQ(test::read_file(path("t.off")),
            "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  write_mesh(t, path("t.obj"), "obj");
  EXPECT_EQ(test::read_file(path("t.obj")),
            "# written by scallop\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  Mesh n = t;
  n.normals.assign(4, V(0, 0, -1));
  write_mesh(n, path("n.off"), "off");
  EXPECT_EQ(test::read_file(path("n.off")).substr(0, 29), "NOFF\n4 4 0\n0 0 0 0 0 -1\n1 0 0");
}

TEST_F(WriteMesh, OffAndObjRoundTripsAreExact) {
  const Mesh m = full_cube();
  write_mesh(m, path("c.off"), "off");
  Mesh r = read_mesh(path("c.off"));
  EXPECT_EQ(r.vertices, m.vertices);
  EXPECT_EQ(r.normals, m.normals);  // NOFF
  expect_same_faces(r, m);
  write_mesh(m, path("c.obj"), "obj");
  r = read_mesh(path("c.obj"));
  EXPECT_EQ(r.vertices, m.vertices);
  expect_same_faces(r, m);
  EXPECT_FALSE(r.has_normals());
}

TEST_F(WriteMesh, StlIsBinaryFanTriangulatedAndWeldsBackToTheCube) {
  const Mesh cube = test::unit_cube();
  write_mesh(cube, path("c.stl"), "stl");
  const std::string s = test::read_file(path("c.stl"));
  ASSERT_EQ(s.size(), 84u + 12 * 50);
  EXPECT_EQ(s.substr(0, 29), "binary STL written by scallop");  // not "solid": no reader takes it for ascii
  EXPECT_EQ(s.substr(80, 4), test::le<std::uint32_t>(12));
  // the first triangle is the bottom quad's first fan triangle, its facet normal -z
  EXPECT_EQ(s.substr(84, 12), test::le(0.f) + test::le(0.f) + test::le(-1.f));
  const Mesh r = read_mesh(path("c.stl"));
  ASSERT_EQ(r.num_vertices(), 8u);  // STL has no shared vertices: welded
  ASSERT_EQ(r.num_faces(), 12u);
  EXPECT_TRUE(r.all_triangles());
  // face 2q and 2q+1 are quad q's fan (c0 c1 c2) and (c0 c2 c3), at the same places
  for (std::size_t q = 0; q < 6; ++q) {
    const auto c = corners(cube, q);
    const std::uint32_t fan[2][3] = {{c[0], c[1], c[2]}, {c[0], c[2], c[3]}};
    for (int t = 0; t < 2; ++t)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(r.vertices[r.face(2 * q + t)[k]], cube.vertices[fan[t][k]]) << q << " " << t;
  }
  // the tetrahedron's triangles come back as they were, vertices numbered as first met
  write_mesh(test::tetrahedron(), path("t.stl"), "stl");
  const Mesh t = read_mesh(path("t.stl"));
  EXPECT_EQ(t.vertices, (std::vector<V>{V(0, 0, 0), V(0, 1, 0), V(1, 0, 0), V(0, 0, 1)}));
  EXPECT_EQ(t.face_vertices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 1, 2, 1, 3}));
}

TEST_F(WriteMesh, FormatOfAndErrors) {
  EXPECT_EQ(mesh_format_of("a/b.PLY"), "ply");
  EXPECT_EQ(mesh_format_of("x.Stl"), "stl");
  EXPECT_EQ(mesh_format_of("x.xyz"), "");
  EXPECT_EQ(mesh_format_of("noext"), "");
  try {
    write_mesh(test::tetrahedron(), path("t.vrml"), "vrml");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "unknown mesh format 'vrml' (expected ply, off, obj or stl)");
  }
  const std::string bad = path("no/such/t.off");
  try {
    write_mesh(test::tetrahedron(), bad, "off");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write '" + bad + "': No such file or directory");
  }
}

// ---------------------------------------------------------------- node

// Runs io.write_mesh on `mesh` with `params` into `out_dir`; returns the file and fills `warnings`.
std::shared_ptr<const FileRef> run_write(const Mesh& mesh, const nlohmann::json& params, const std::string& out_dir,
                                         std::vector<std::string>* warnings = nullptr) {
  const NodeDecl d = make_write_mesh_node();
  nlohmann::json p = {{"format", "auto"}};
  p.update(params);
  NodeContext ctx(d, "save", "part", p, {{"mesh", std::make_shared<Mesh>(mesh)}}, nullptr,
                  [&](const std::string& m) {
                    if (warnings) warnings->push_back(m);
                  });
  ctx.set_output_dir(out_dir);
  d.run(ctx);
  return std::dynamic_pointer_cast<const FileRef>(ctx.take_outputs().at("file"));
}

TEST_F(WriteMesh, NodeChoosesTheFormatByExtensionOrParameter) {
  const NodeDecl d = make_write_mesh_node();
  EXPECT_EQ(d.type, "io.write_mesh");
  EXPECT_EQ(d.find_input("mesh")->type, "Mesh");
  EXPECT_EQ(d.find_output("file")->type, "File");
  EXPECT_TRUE(d.find_param("path")->output_path);
  EXPECT_EQ(d.find_param("format")->default_value, "auto");
  EXPECT_FALSE(d.cache_on_disk);

  const Mesh t = test::tetrahedron();
  auto f = run_write(t, {{"path", "sub/t.obj"}}, dir_.str());
  EXPECT_EQ(f->path, path("sub/t.obj"));
  EXPECT_EQ(test::read_file(f->path).substr(0, 20), "# written by scallop");
  // an explicit format wins over the extension
  f = run_write(t, {{"path", "t.mesh"}, {"format", "off"}}, dir_.str());
  EXPECT_EQ(test::read_file(f->path).substr(0, 4), "OFF\n");
}

TEST_F(WriteMesh, NodeSaysWhatTheFormatDrops) {
  std::vector<std::string> warnings;
  run_write(full_cube(), {{"path", "c.stl"}}, dir_.str(), &warnings);
  run_write(full_cube(), {{"path", "c.off"}}, dir_.str(), &warnings);
  run_write(full_cube(), {{"path", "c.ply"}}, dir_.str(), &warnings);
  EXPECT_EQ(warnings, (std::vector<std::string>{
                          "stl keeps no face labels, feature edges and vertex normals: they are not in 'c.stl' (PLY keeps them)",
                          "off keeps no face labels and feature edges: they are not in 'c.off' (PLY keeps them)"}));
}

TEST_F(WriteMesh, NodeWritesInsideTheOutputFolderOnly) {
  const Mesh t = test::tetrahedron();
  const std::string out = path("out"), abs = path("abs.stl");
  for (const auto& [param, why] :
       {std::pair<std::string, std::string>{"../x.stl", "'../x.stl' would be written outside the output folder"},
        {abs, std::string(1, '\'').append(abs).append("' is absolute: it would be written outside the output folder")}}) {
    try {
      run_write(t, {{"path", param}}, out);
      ADD_FAILURE() << "no error for " << param;
    } catch (const NodeError& e) {
      EXPECT_EQ(std::string(e.what()), "parameter 'path': " + why + "; expected a relative path inside it, without '..'");
    }
  }
  EXPECT_FALSE(std::filesystem::exists(path("x.stl")));
  EXPECT_FALSE(std::filesystem::exists(path("abs.stl")));
  try {
    run_write(t, {{"path", "t.xyz"}}, out);
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'path': 't.xyz' has no mesh extension (.ply .off .obj .stl); give one, or set 'format'");
  }
  try {
    run_write(t, {{"path", ""}}, out);
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'path' is empty: give the file to write");
  }
}

}  // namespace
}  // namespace scallop
