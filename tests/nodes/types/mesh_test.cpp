#include "nodes/types/mesh.h"

#include <gtest/gtest.h>

#include <sstream>

#include "nodes/types/ply_writer.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// A unit square split into a triangle and a quad-less fan: one quad and one triangle.
Mesh square_and_triangle() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
  m.add_face({0, 1, 2, 3});
  m.add_face({1, 4, 2});
  m.face_label = {3, -1};
  m.feature_edges = {{{1, 2}}};
  return m;
}

TEST(Mesh, CacheFormRoundTripsEveryArray) {
  Mesh m = square_and_triangle();
  m.normals.assign(m.num_vertices(), Eigen::Vector3d(0, 0, 1));
  std::stringstream s;
  m.serialize(s);
  auto back = std::dynamic_pointer_cast<const Mesh>(Mesh::deserialize(s));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->vertices, m.vertices);
  EXPECT_EQ(back->face_start, m.face_start);
  EXPECT_EQ(back->face_vertices, m.face_vertices);
  EXPECT_EQ(back->normals, m.normals);
  EXPECT_EQ(back->face_label, m.face_label);
  EXPECT_EQ(back->feature_edges, m.feature_edges);
  EXPECT_EQ(back->num_faces(), 2u);
  EXPECT_EQ(back->face_size(0), 4u);
  EXPECT_FALSE(back->all_triangles());
}

TEST(Mesh, ACacheEntryIndexingPastTheVerticesIsRefused) {
  Mesh m = square_and_triangle();
  m.face_vertices[5] = 99;  // the triangle's second corner
  std::stringstream s;
  m.serialize(s);
  try {
    Mesh::deserialize(s);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "corrupt mesh: vertex index");
  }
}

TEST(Mesh, PlyHeaderListsFacesLabelsAndFeatureEdges) {
  test::TempDir dir;
  const auto path = dir.path / "m.ply";
  square_and_triangle().write_file(path.string());
  const std::string text = test::read_file(path);
  const std::string header = text.substr(0, text.find("end_header\n") + 11);
  EXPECT_EQ(header,
            "ply\nformat binary_little_endian 1.0\ncomment written by scallop\n"
            "element vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
            "element face 2\nproperty list uchar uint vertex_indices\nproperty int label\n"
            "element edge 1\nproperty uint vertex1\nproperty uint vertex2\nproperty uchar feature\n"
            "end_header\n");
  // 5 vertices of 24 bytes, faces of 1 + 4n + 4 bytes, one edge of 9 bytes.
  EXPECT_EQ(text.size(), header.size() + 5 * 24 + (1 + 16 + 4) + (1 + 12 + 4) + 9);
}

}  // namespace
}  // namespace scallop
