// Sharp edges of a mesh chained into feature curves, with their corners (mesh.sharp_edges).
//
// An edge with two faces is sharp when the angle between the faces' normals (the dihedral angle's
// supplement: 0 for a flat edge, 90 degrees on a cube's edge) exceeds theta; the paper's
// segmentation takes theta = 50 degrees (papers/point-clouds-to-workpieces.md). Sharp edges are
// chained into curves through vertices where exactly two sharp edges meet; a curve ends at a
// vertex with one sharp edge (a feature fading out) or with three or more (a corner). A chain
// whose every vertex has two sharp edges is a closed curve. Edges on the boundary (one face) and
// edges with three or more faces have no dihedral angle and are never sharp. An edge whose faces
// turn by more than fold_deg is a fold of the mesh (a face turned over onto its neighbour, as
// mesh.sharpen can leave beside a part's edge), not an edge of the part: counted, not sharp.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/mesh.h"

namespace scallop {

struct FeatureCurve {
  std::vector<std::uint32_t> vertices;  // along the curve; a closed curve does not repeat its first
  bool closed = false;
  double length = 0;  // mm
};

struct SharpEdges {
  std::vector<std::array<std::uint32_t, 2>> edges;  // sharp edges as vertex pairs (a < b), sorted
  std::vector<FeatureCurve> curves;                 // open curves first (by first vertex), then closed
  std::vector<std::uint32_t> corners;               // vertices with 3 or more sharp edges, increasing
  double length = 0;                                // mm, all sharp edges
  std::size_t boundary_edges = 0, non_manifold_edges = 0;  // not rated
  std::size_t folds = 0;                                   // edges turning by more than fold_deg
};

// mesh       any polygon mesh (faces without area have no normal: their edges are not sharp)
// edges      mesh_edges(mesh)
// angle_deg  theta in degrees, in [0, 180)
// fold_deg   in (theta, 180]; 180: no edge is a fold
// Throws std::invalid_argument for theta outside [0, 180) or fold_deg outside (theta, 180].
SharpEdges sharp_edges(const Mesh& mesh, const MeshEdges& edges, double angle_deg, double fold_deg = 180);

}  // namespace scallop
