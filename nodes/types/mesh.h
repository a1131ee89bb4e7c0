// Polygon mesh value: the second method's surface (cloud -> mesh -> denoise -> quads -> patches).
#pragma once

#include <Eigen/Core>
#include <array>
#include <initializer_list>
#include <iterator>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

// V  #V by 3 vertex positions (mm).
// Faces are polygons of any size >= 3 (triangles, quads, mixed), stored flat:
//   face_start  #F+1 offsets into face_vertices; face f is face_vertices[face_start[f] ..
//               face_start[f+1]), its corners counter-clockwise seen from outside.
// N  #V unit vertex normals, or empty.
// face_label  #F patch labels (segmentation fills them; -1 unlabelled), or empty.
// feature_edges  undirected vertex pairs (a < b) flagged as sharp feature edges, or empty;
//                each is an edge of some face.
struct Mesh final : Value {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::uint32_t> face_start{0};
  std::vector<std::uint32_t> face_vertices;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::int32_t> face_label;
  std::vector<std::array<std::uint32_t, 2>> feature_edges;

  std::size_t num_vertices() const { return vertices.size(); }
  std::size_t num_faces() const { return face_start.empty() ? 0 : face_start.size() - 1; }
  std::size_t face_size(std::size_t f) const { return face_start[f + 1] - face_start[f]; }
  const std::uint32_t* face(std::size_t f) const { return face_vertices.data() + face_start[f]; }
  // Appends a face given by its corner indices.
  void add_face(std::initializer_list<std::uint32_t> corners) {
    face_vertices.insert(face_vertices.end(), corners.begin(), corners.end());
    face_start.push_back(static_cast<std::uint32_t>(face_vertices.size()));
  }
  template <class Range>
  void add_face_range(const Range& corners) {
    face_vertices.insert(face_vertices.end(), std::begin(corners), std::end(corners));
    face_start.push_back(static_cast<std::uint32_t>(face_vertices.size()));
  }
  bool has_normals() const { return !normals.empty() && normals.size() == vertices.size(); }
  bool has_labels() const { return !face_label.empty() && face_label.size() == num_faces(); }
  bool all_triangles() const { return face_vertices.size() == 3 * num_faces(); }
  // The same faces over as many vertices: a copy of `other` with its vertices moved.
  bool same_faces(const Mesh& other) const {
    return vertices.size() == other.vertices.size() && face_start == other.face_start &&
           face_vertices == other.face_vertices;
  }

  std::string type_name() const override { return "Mesh"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // Writes binary little-endian PLY: vertex (x y z [nx ny nz] double), face (vertex_indices,
  // [label int]), edge (vertex1 vertex2, feature uchar) when there are feature edges.
  void write_file(const std::string& path) const override;
};

}  // namespace scallop
