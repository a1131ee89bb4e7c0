// Per-face geometry of a polygon mesh: unit normals, areas, centroids; vertex normals; and the angle between two
// directions. What the mesh filters (mesh.denoise) and mesh.sharp_edges measure faces with.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// normal    #F unit normals: Newell's vector (as face_area_vector, taken about the face's first
//           corner) normalised; zero for a face without area
// area      #F areas (mm^2), half the length of Newell's vector
// centroid  #F means of each face's corners (mm)
struct FaceGeometry {
  std::vector<Eigen::Vector3d> normal;
  std::vector<double> area;
  std::vector<Eigen::Vector3d> centroid;
};

// Computed in parallel. The mesh's corners must index its vertices.
FaceGeometry face_geometry(const Mesh& mesh);
// The same for the mesh's faces at other vertex positions V (#V by 3).
FaceGeometry face_geometry(const Mesh& mesh, const std::vector<Eigen::Vector3d>& V);

// Unit vertex normals weighted by the faces' corner angles (a cube's edge: the bisector, its corner:
// the diagonal), zero at a vertex without a face of any area.
std::vector<Eigen::Vector3d> vertex_normals(const Mesh& mesh);

// Angle between a and b in degrees, in [0, 180]; atan2(|a x b|, a . b), accurate also near 0 and 180.
// 0 when either is zero.
double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// Faces `faces` of `mesh` fanned from their first corner into triangles over a compact vertex
// list of their own (what CGAL's polygon-soup functions take): points holds each corner used
// once, in order of first use; first_triangle[k] is the index of face faces[k]'s first triangle.
struct FannedTriangles {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<std::size_t, 3>> triangles;
  std::vector<std::size_t> first_triangle;
};
FannedTriangles fan_triangles(const Mesh& mesh, const std::vector<std::size_t>& faces);

}  // namespace scallop
