// Where a closed mesh crosses itself, and the faces beside those crossings that face into it.
// A reconstruction from a cloud tangles where the part has a gap narrower than its points resolve:
// the ABC plate's pin of radius 0.635 mm in a bore 0.245 mm wider, at 0.1 mm spacing, came out a
// closed, consistently oriented mesh that crosses itself, the pin's faces turned into the part
// (docs/workpiece.md, stop 59). A ball kept off such faces, or a gouge measured against them, says
// nothing about the part there.
//
// A face is tangled when it crosses another face (more than a shared corner or edge), or when it
// shares an edge with a tangled face and the point just off its centre along its normal lies inside
// the mesh by the parity of three rays (majority): it faces inward.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

struct SelfCrossings {
  std::vector<std::array<std::size_t, 2>> pairs;  // crossing faces (polygon indices), smaller first, sorted
  std::vector<std::size_t> tangled;               // the faces that cross and those grown from them facing inward, sorted
  std::size_t inward = 0;                         // of `tangled`, those added for facing inward (the others cross)
  std::size_t faces_left_out = 0;  // polygons that do not fit a manifold surface with the ones before them: not checked
};

// mesh  any polygons (each fanned from its first corner), closed for the inward test to mean
//       anything; faces without area are left out of both tests.
SelfCrossings self_crossings(const Mesh& mesh);

// What a tool must keep off around tangled faces: the part may lie anywhere within margin / 2 of
// them, margin being twice the tangled faces' mean edge length (a reconstruction's edges are about
// its cloud's spacing, and the gap it did not resolve about that wide: the ABC plate's pin corner
// stood 0.135 mm outside its outer mesh where the tangled faces' edges average 0.245 mm). A ball
// centre kept r + margin from every sample stays r + margin / 4 from such a part: every point of
// a tangled face lies within margin / 4 of a sample (each triangle of the fan cut into a lattice
// of triangles whose edges are at most that). None without tangled faces.
// That is a reconstruction's rule. A mesh given as the part itself (a CAD mesh whose facets fold
// over one another: the block's, with facets 3.6 to 13 mm long, had a margin of 12.7 mm, and its
// bores were left uncut, 8.2 % of the part) is where the part is even where it crosses itself:
// `margin` 0 gives no keep-out; > 0 a margin of one's own; < 0 the rule above.
struct TangleKeepOut {
  std::vector<Eigen::Vector3d> samples;
  double margin = 0;  // mm
};
TangleKeepOut tangle_keep_out(const Mesh& mesh, const SelfCrossings& crossings, double margin = -1);
// The margin a node's option `tangle_margin` asks for: the option when given (>= 0); otherwise the
// reconstruction's rule (-1) for a mesh made from a cloud, none (0) for a mesh given as the part.
inline double tangle_margin_for(double option, bool made_from_cloud) {
  return option >= 0 ? option : made_from_cloud ? -1.0 : 0.0;
}

}  // namespace scallop
