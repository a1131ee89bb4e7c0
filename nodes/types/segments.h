// Segmentation value: a quad mesh split into sharp height fields (SHF), each a rectangle of the
// quad grid that a 3-axis machine reaches from one direction (paper 2, "Optimal surface
// segmentation for CNC").
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/value.h"
#include "nodes/types/mesh.h"

namespace scallop {

// One SHF.
//   direction       unit machining direction: the tool axis, pointing from the surface to the
//                   spindle; every face's outward normal n has n . direction >= min_normal_dot.
//   faces           the patch's faces (indices into Segments::mesh) cell by cell: the face between
//                   grid rows i, i+1 and columns j, j+1 is faces[i * (cols-1) + j].
//   rows, cols      the patch as a regular grid of mesh vertices, rows by cols (>= 2 each):
//   grid            row-major vertex indices, grid[i * cols + j]; the four corners are
//                   grid(0,0), grid(0,cols-1), grid(rows-1,cols-1), grid(rows-1,0), counter-
//                   clockwise seen from the spindle (looking along -direction). The outline is
//                   the grid's border. Row i = 0 is the v = 0 edge of the rectangle map, column
//                   j = 0 the u = 0 edge: (u, v) = (j / (cols-1), i / (rows-1)) on the grid.
struct SegmentPatch {
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double min_normal_dot = 1.0;
  std::vector<std::uint32_t> faces;
  std::uint32_t rows = 0, cols = 0;
  std::vector<std::uint32_t> grid;

  std::uint32_t at(std::uint32_t i, std::uint32_t j) const { return grid[std::size_t(i) * cols + j]; }
};

// mesh            the quad mesh the patches cut (the setup base removed), face_label[f] = the
//                 patch of face f, feature_edges = its sharp edges.
// patches         the SHFs; together they hold every face of mesh exactly once.
// clipping_edges  undirected vertex pairs (a < b) of the edges the patches were cut along.
// base_direction  unit outward normal of the clamping base (the part rests on it; it is not
//                 machined in any setup), or zero when the part has no base.
struct Segments final : Value {
  Mesh mesh;
  std::vector<SegmentPatch> patches;
  std::vector<std::array<std::uint32_t, 2>> clipping_edges;
  Eigen::Vector3d base_direction = Eigen::Vector3d::Zero();

  std::string type_name() const override { return "Segments"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
  // Writes the labelled mesh as PLY (face label = patch), clipping edges as its feature edges.
  void write_file(const std::string& path) const override;
};

}  // namespace scallop
