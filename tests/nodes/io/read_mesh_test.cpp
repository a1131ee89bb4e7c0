// Tests for the mesh readers (OFF, OBJ, STL, PLY with faces), read_mesh and the io.read_mesh node.
#include "nodes/io/read_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/write_mesh.h"
#include "nodes/types/document.h"
#include "tests/nodes/io/bytes.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace io_nodes {
NodeDecl make_read_mesh_node();
}  // namespace io_nodes
using io_nodes::make_read_mesh_node;
}  // namespace scallop

namespace scallop {
namespace {

using test::be;
using test::corners;
using test::le;
using V = Eigen::Vector3d;
using Faces = std::vector<std::vector<std::uint32_t>>;

class ReadMesh : public ::testing::Test {
 protected:
  // Writes `bytes` to a file of that name in a fresh folder and returns its path.
  std::string file(const std::string& name, const std::string& bytes) {
    const std::string p = (dir_.path / name).string();
    test::write_file(p, bytes);
    return p;
  }
  test::TempDir dir_;
};

// The message read_mesh throws for `path`, or "<no error>".
std::string error_of(const std::string& path, double scale = 1.0) {
  try {
    read_mesh(path, scale);
  } catch (const CloudReadError& e) {
    return e.what();
  }
  return "<no error>";
}

Faces faces_of(const Mesh& m) {
  Faces f;
  for (std::size_t i = 0; i < m.num_faces(); ++i) f.push_back(corners(m, i));
  return f;
}

// The tetrahedron of mesh_test_util.h as an STL triangle list.
std::vector<std::array<V, 3>> tetra_triangles() {
  const Mesh t = test::tetrahedron();
  std::vector<std::array<V, 3>> tris;
  for (std::size_t f = 0; f < t.num_faces(); ++f)
    tris.push_back({t.vertices[t.face(f)[0]], t.vertices[t.face(f)[1]], t.vertices[t.face(f)[2]]});
  return tris;
}

std::string stl_ascii(const std::vector<std::array<V, 3>>& tris) {
  std::string s = "solid tetra\n";
  for (const auto& t : tris) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (const V& v : t) s += "   vertex " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + "\n";
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid tetra\n";
}

std::string stl_binary(const std::vector<std::array<V, 3>>& tris) {
  std::string s(80, ' ');
  s += le<std::uint32_t>(static_cast<std::uint32_t>(tris.size()));
  for (const auto& t : tris) {
    s += le(0.f) + le(0.f) + le(0.f);
    for (const V& v : t)
      for (int k = 0; k < 3; ++k) s += le(static_cast<float>(v[k]));
    s += le<std::uint16_t>(0);
  }
  return s;
}

// ---------------------------------------------------------------- formats

TEST_F(ReadMesh, OffQuadsTrianglesColoursAndNormals) {
  // a pyramid: a quad base and four triangles, one with a colour after its indices
  const std::string body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 3 2 1\n3 0 1 4 255 0 0\n3 1 2 4\n3 2 3 4\n3 3 0 4\n";
  const Mesh m = read_mesh(file("p.off", "OFF\n# a pyramid\n5 5 0\n" + body));
  EXPECT_EQ(m.vertices, (std::vector<V>{V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0), V(0.5, 0.5, 1)}));
  EXPECT_EQ(faces_of(m), (Faces{{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}));
  EXPECT_FALSE(m.has_normals());
  const Mesh n = read_mesh(file("n.off", "NOFF 3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"));
  EXPECT_EQ(n.normals, std::vector<V>(3, V(0, 0, 1)));
  EXPECT_EQ(faces_of(n), (Faces{{0, 1, 2}}));
}

TEST_F(ReadMesh, ObjCornerFormsNegativeAndForwardIndices) {
  const Mesh m = read_mesh(file("a.obj",
                                "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\ng top\nusemtl x\n"
                                "f 1/1/1 2/1/1 3/1/1\nf -3//1 -1//1 4//1\nv 0 1 0\nl 1 2\nf 1/1 3/1 4/1\n"));
  EXPECT_EQ(m.vertices.size(), 4u);
  // -3 and -1 count back from the third vertex, the last read then; 4 is defined further down
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {0, 2, 3}, {0, 2, 3}}));
  EXPECT_FALSE(m.has_normals());
}

TEST_F(ReadMesh, StlAsciiAndBinaryWeldTheTetrahedronToFourVertices) {
  const Faces want = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {2, 1, 3}};  // first appearance: 0, (0,1,0), (1,0,0), (0,0,1)
  const std::vector<V> verts = {V(0, 0, 0), V(0, 1, 0), V(1, 0, 0), V(0, 0, 1)};
  for (const std::string& p : {file("a.stl", stl_ascii(tetra_triangles())), file("b.stl", stl_binary(tetra_triangles()))}) {
    const Mesh m = read_mesh(p);
    EXPECT_EQ(m.vertices, verts) << p;
    EXPECT_EQ(faces_of(m), want) << p;
  }
}

TEST_F(ReadMesh, PlyAsciiFacesLabelsAndFeatureEdges) {
  const std::string s =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "element face 2\nproperty list uchar float texcoord\nproperty list uchar int vertex_indices\nproperty int label\n"
      "element edge 2\nproperty int vertex1\nproperty int vertex2\nproperty uchar feature\nend_header\n"
      "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n"
      "2 0.5 0.5 3 0 1 2 7\n0 3 0 2 3 -1\n"
      "2 0 1\n0 2 0\n";
  const Mesh m = read_mesh(file("a.ply", s));
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2}, {0, 2, 3}}));
  EXPECT_EQ(m.face_label, (std::vector<std::int32_t>{7, -1}));
  EXPECT_EQ(m.normals, std::vector<V>(4, V(0, 0, 1)));
  // the edge 2-0 is flagged (stored a < b), 0-2's twin line is not
  EXPECT_EQ(m.feature_edges, (std::vector<std::array<std::uint32_t, 2>>{{0, 2}}));
}

TEST_F(ReadMesh, PlyBinaryBigEndianFaceBeforeVerticesAndVertexIndexName) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar uint vertex_index\n"
      "element vertex 4\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  s += be<std::uint8_t>(4) + be<std::uint32_t>(0) + be<std::uint32_t>(1) + be<std::uint32_t>(2) + be<std::uint32_t>(3);
  for (double v : {0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 1.5, 2.5, 0.0, 0.0, 2.5, 0.0}) s += be(v);
  const Mesh m = read_mesh(file("be.ply", s));
  EXPECT_EQ(m.vertices, (std::vector<V>{V(0, 0, 0), V(1.5, 0, 0), V(1.5, 2.5, 0), V(0, 2.5, 0)}));
  EXPECT_EQ(faces_of(m), (Faces{{0, 1, 2, 3}}));
  EXPECT_FALSE(m.has_labels());
}

TEST_F(ReadMesh, ScaleAndExtensionCase) {
  const Mesh m = read_mesh(file("a.OFF", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), 1000);
  EXPECT_EQ(m.vertices, (std::vector<V>{V(0, 0, 0), V(1000, 0, 0), V(0, 1000, 0)}));
}

// ---------------------------------------------------------------- bad files

TEST_F(ReadMesh, FacesIndexingPastTheVerticesNameTheirLineOrByte) {
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  std::string p = file("bad.off", "OFF\n3 1 0\n" + tri + "3 0 1 3\n");
  EXPECT_EQ(error_of(p), p + ": line 6: face 0 has index '3' but there are 3 vertices");
  p = file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n# end\n");
  EXPECT_EQ(error_of(p), p + ": line 5: face 1 has index '4' but there are 3 vertices");
  p = file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 4: face 0 has index '-4' but there are 3 vertices");
  p = file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 4: bad vertex index '0' in face 0 (OBJ counts vertices from 1, or back from -1)");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  p = file("bad.ply", head + tri + "3 0 1 2\n3 0 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 14: face 1 has index '3' but there are 3 vertices");
  p = file("bad.ply", head + tri + "3 0 1 2\n3 0 -1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 14: face 1 has index '-1' but there are 3 vertices");
  // binary: the byte where the face starts
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) s += le(v);
  const std::size_t face = s.size();
  p = file("bad_binary.ply", s + le<std::uint8_t>(3) + le<std::int32_t>(0) + le<std::int32_t>(7) + le<std::int32_t>(1));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(face) + ": face 0 has index '7' but there are 3 vertices");
  // a feature edge too
  p = file("bad_edge.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list uchar int vertex_indices\n"
                           "element edge 1\nproperty int vertex1\nproperty int vertex2\nproperty uchar feature\nend_header\n" +
                               tri + "3 0 1 2\n0 9 1\n");
  EXPECT_EQ(error_of(p), p + ": line 18: edge 0 has index '9' but there are 3 vertices");
}

TEST_F(ReadMesh, TruncatedAndMalformedStl) {
  const std::string full = stl_binary(tetra_triangles());
  std::string p = file("cut.stl", full.substr(0, full.size() - 10));
  EXPECT_EQ(error_of(p), p + ": byte 234: file ends inside triangle 3 of 4");
  p = file("tiny.stl", "tiny");
  EXPECT_EQ(error_of(p), p + ": byte 0: file too short for a binary STL header (84 bytes)");
  p = file("two.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_EQ(error_of(p), p + ": line 6: facet 0 has 2 vertices, expected 3");
}

TEST_F(ReadMesh, NaNAndInfiniteCoordinatesAreRefusedWhereTheyAre) {
  std::string p = file("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 4: vertex 1 has a NaN coordinate");
  p = file("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 -inf 0\n3 0 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 5: vertex 2 has an infinite coordinate");
  p = file("nan.obj", "v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 2: vertex 1 has a NaN coordinate");
  p = file("nan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 nan\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_EQ(error_of(p), p + ": line 5: facet 0 has a NaN coordinate");
  auto tris = tetra_triangles();
  tris[1][2].y() = std::numeric_limits<double>::quiet_NaN();
  p = file("nan_binary.stl", stl_binary(tris));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(84 + 50 + 12 + 24) + ": corner 2 of triangle 1 has a NaN coordinate");
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::size_t v1 = s.size() + 12;
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, std::numeric_limits<float>::infinity(), 0.f, 1.f, 0.f}) s += le(v);
  p = file("inf.ply", s + le<std::uint8_t>(3) + le<std::int32_t>(0) + le<std::int32_t>(1) + le<std::int32_t>(2));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(v1) + ": vertex 1 has an infinite coordinate");
}

TEST_F(ReadMesh, FilesThatAreNoMesh) {
  std::string p = file("empty.stl", "");
  EXPECT_EQ(error_of(p), p + ": file is empty");
  p = file("points.off", "OFF\n2 0 0\n1 2 3\n4 5 6\n");
  EXPECT_EQ(error_of(p), p + ": no faces (2 vertices): a point cloud, not a mesh; read it with io.read_cloud");
  p = file("points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                         "end_header\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": no faces (1 vertex): a point cloud, not a mesh; read it with io.read_cloud");
  p = file("points.obj", "v 1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": no faces (1 vertex): a point cloud, not a mesh; read it with io.read_cloud");
  p = file("edge.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  EXPECT_EQ(error_of(p), p + ": line 6: face 0 has 2 corners; a face needs at least 3");
  p = file("edge.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 3: face 0 has 2 corners; a face needs at least 3");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  p = file("edge.ply", head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  EXPECT_EQ(error_of(p), p + ": line 13: face 0 has 2 corners; a face needs at least 3");
  p = file("noindices.ply", head + "element face 1\nproperty int label\nend_header\n0 0 0\n1 0 0\n0 1 0\n4\n");
  EXPECT_EQ(error_of(p), p + ": line 9: face element has no 'vertex_indices' list property");
  p = file("float.ply", head + "element face 1\nproperty list uchar float vertex_indices\nend_header\n");
  EXPECT_EQ(error_of(p), p + ": line 9: face property 'vertex_indices' holds 'float' values; vertex indices must be integers");
  p = file("a.xyz", "1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": unsupported extension '.xyz' (expected .ply .off .obj .stl)");
  p = file("a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(error_of(p, -1), p + ": scale must be positive and finite, got -1");
}

// Binary garbage and every cut of a valid binary PLY and STL: an error, never a crash.
TEST_F(ReadMesh, GarbageAndCutFilesFailCleanly) {
  std::string junk;
  std::uint32_t x = 12345;
  for (int i = 0; i < 3000; ++i) {
    x = x * 1664525u + 1013904223u;
    junk.push_back(static_cast<char>(x >> 24));
  }
  for (const char* ext : {".ply", ".off", ".obj", ".stl"})
    EXPECT_NE(error_of(file(std::string("junk") + ext, junk)), "<no error>") << ext;
  Mesh cube = test::unit_cube();
  cube.face_label = {0, 1, 2, 3, 4, 5};
  cube.feature_edges = {{{0, 1}}};
  write_mesh(cube, (dir_.path / "full.ply").string(), "ply");
  write_mesh(cube, (dir_.path / "full.stl").string(), "stl");
  for (const char* name : {"full.ply", "full.stl"}) {
    const std::string full = test::read_file(dir_.path / name);
    for (std::size_t n = 1; n < full.size(); n += 5)
      EXPECT_NE(error_of(file(std::string("cut_") + name, full.substr(0, n))), "<no error>") << name << " " << n;
  }
}

// ---------------------------------------------------------------- node

// Runs io.read_mesh on `path`; returns its outputs and fills `warnings`.
std::map<std::string, ValuePtr> run_read(const std::string& path, double scale, std::vector<std::string>& warnings) {
  const NodeDecl d = make_read_mesh_node();
  NodeContext ctx(d, "read", "part", {{"scale", scale}}, {{"file", std::make_shared<FileRef>(FileRef::open(path))}},
                  nullptr, [&](const std::string& m) { warnings.push_back(m); });
  d.run(ctx);
  return ctx.take_outputs();
}

TEST_F(ReadMesh, NodeReportsTheTopology) {
  const NodeDecl d = make_read_mesh_node();
  EXPECT_EQ(d.type, "io.read_mesh");
  EXPECT_EQ(d.find_input("file")->type, "File");
  EXPECT_EQ(d.find_output("mesh")->type, "Mesh");
  EXPECT_EQ(d.find_output("report")->type, "Report");
  EXPECT_EQ(d.find_param("scale")->default_value, 1.0);

  std::vector<std::string> warnings;
  const std::string cube = (dir_.path / "cube.off").string();
  write_mesh(test::unit_cube(), cube, "off");
  auto out = run_read(cube, 10, warnings);
  auto mesh = std::dynamic_pointer_cast<const Mesh>(out.at("mesh"));
  ASSERT_TRUE(mesh);
  EXPECT_EQ(mesh->vertices[7], V(10, 10, 10));
  auto report = std::dynamic_pointer_cast<const Report>(out.at("report"));
  ASSERT_TRUE(report);
  EXPECT_EQ(report->data, (nlohmann::json{{"file", cube},
                                          {"vertices", 8},
                                          {"faces", 6},
                                          {"edges", 12},
                                          {"triangles", 0},
                                          {"quads", 6},
                                          {"other_polygons", 0},
                                          {"components", 1},
                                          {"boundary_loops", 0},
                                          {"genus", 0},
                                          {"non_manifold_edges", 0},
                                          {"degenerate_faces", 0},
                                          {"isolated_vertices", 0},
                                          {"closed", true}}));
  EXPECT_TRUE(warnings.empty());

  // STL: 12 corners welded to 4 vertices; a sliver whose corners weld together is counted
  auto tris = tetra_triangles();
  tris.push_back({V(0, 0, 0), V(1, 0, 0), V(1, 0, 0)});
  out = run_read(file("t.stl", stl_binary(tris)), 1, warnings);
  report = std::dynamic_pointer_cast<const Report>(out.at("report"));
  EXPECT_EQ(report->data["corners_welded"], 11);
  EXPECT_EQ(report->data["triangles"], 5);
  EXPECT_EQ(report->data["degenerate_faces"], 1);
  EXPECT_EQ(report->data["non_manifold_edges"], 1);  // the sliver lies on the edge (0,0,0)-(1,0,0)
  EXPECT_EQ(report->data["genus"], -1);
}

TEST_F(ReadMesh, NodeRefusesBadFilesAsInputAndWarnsAboutUnits) {
  std::vector<std::string> warnings;
  std::string p = file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  try {
    run_read(p, 1, warnings);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), p + ": line 6: face 0 has index '3' but there are 3 vertices");
  }
  p = file("far.off", "OFF\n3 1 0\n0 0 0\n1e300 0 0\n0 1 0\n3 0 1 2\n");
  try {
    run_read(p, 1, warnings);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              p + ": point 1 at (1e+300, 0, 0): coordinates out of range (beyond 1e9 mm); the file is damaged or its scale is wrong");
  }
  // a 100 mm part in metres; a coarse CAD mesh (vertices 100 mm apart) is not warned about
  run_read(file("metres.off", "OFF\n3 1 0\n0 0 0\n0.1 0 0\n0 0.1 0\n3 0 1 2\n"), 1, warnings);
  EXPECT_EQ(warnings, (std::vector<std::string>{
                          "the mesh is 0.1 mm across: is it in metres? coordinates are read as mm; set read.scale to 1000"}));
  warnings.clear();
  run_read(file("coarse.off", "OFF\n3 1 0\n0 0 0\n500 0 0\n0 500 0\n3 0 1 2\n"), 1, warnings);
  EXPECT_TRUE(warnings.empty());
}

}  // namespace
}  // namespace scallop
