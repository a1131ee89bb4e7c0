// Distances from points to a mesh's surface (Embree's point query), and rays against it (CGAL's
// AABB tree): for reports that measure a reconstruction or a fitted surface against a mesh, and
// for what a tool axis can reach (surface.setups), and a ball centre inside the part
// (post.simulate_part).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

// Distances to one mesh's faces, asked many times (the AABB tree built once). Thread-safe.
class MeshDistance {
 public:
  // mesh     any polygons, each fanned from its first corner.
  // unmoved  null, or the same faces before mesh's vertices were moved (mesh.cloud_envelope's outer
  //          and inner meshes are its input moved along the normals): a face turned more than 10
  //          degrees against its place there may cross its neighbours, and is left to the rays too
  //          (signed_distance). Faces that differ:
  //          std::invalid_argument.
  // untrusted  faces (polygon indices, any order) whose normals do not tell the side either, left
  //          to the rays as well: self_crossings' tangled faces, turned into the part where a
  //          reconstruction crossed itself (a ball centre 2.5 mm outside the ABC plate read 2.5 mm
  //          inside by one). An index past the faces: std::invalid_argument.
  explicit MeshDistance(const Mesh& mesh, const Mesh* unmoved = nullptr, std::span<const std::size_t> untrusted = {});
  // The same faces, and points the part is known to hold besides (the cloud it was measured at,
  // in the mesh's frame): the distances (unsigned, signed, least_along) are to the union of the
  // solid and the points, the nearer of the faces and the nearest point. Where a mesh made from a
  // cloud does not hold all of it (a fold, a filled hole: 165 of the ABC plate's 200 000 points
  // stood up to 0.36 mm outside its outer mesh), a ball kept off the part is kept off them too.
  // With margin > 0, the part may reach anywhere within `margin` of the points (samples of faces
  // that are no bound on the part, where the mesh crosses itself): the distance to them is less
  // that. Points held before stay held. Rays, closest_point and closest_face see the faces only. A
  // point that is not finite, or a margin that is negative or not finite: std::invalid_argument.
  MeshDistance with_points(const std::vector<Eigen::Vector3d>& points, double margin = 0) const;
  ~MeshDistance();
  MeshDistance(const MeshDistance&) = delete;
  MeshDistance& operator=(const MeshDistance&) = delete;
  MeshDistance(MeshDistance&&) noexcept;
  MeshDistance& operator=(MeshDistance&&) noexcept;
  // The same mesh moved rigidly, x -> rotation x + translation (a setup's machine frame): asked
  // and answered in that frame, the tree shared with this one rather than built again (the
  // fandisk cloud's 408 000 faces took 0.9 s a tree, two for each of 13 setups).
  MeshDistance placed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const;
  // Unsigned distance from p to the nearest point of the faces; +infinity without faces.
  double operator()(const Eigen::Vector3d& p) const;
  // The same, the search started from `hint`, a point on the faces near p (faster).
  double operator()(const Eigen::Vector3d& p, const Eigen::Vector3d& hint) const;
  // The nearest point of the faces to p (p itself without faces).
  Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const;
  // The index of the mesh's face (polygon) that holds the nearest point; SIZE_MAX without faces.
  std::size_t closest_face(const Eigen::Vector3d& p) const;
  // The same, and that nearest point into `at` (one search for both).
  std::size_t closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& at) const;
  // How far along the ray from p in direction d (unit) the first face lies; +infinity when the
  // ray meets none.
  double ray_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& d) const;
  // Signed distance, negative inside the part: the side of the nearest face's outward normal
  // (corners counter-clockwise seen from outside) where the nearest point lies inside a face;
  // where it lies on an edge or a corner, where faces disagree, or on a face folded back onto a
  // neighbour (normals more than 150 degrees apart: it faces the wrong way), turned more than 10
  // degrees against its unmoved place (the moves may have folded it across its neighbours) or
  // named untrusted, the parity of the
  // crossings of three skew rays (majority), which needs a closed mesh. Within 1e-9 mm of the
  // faces, that distance unsigned. +infinity without faces.
  double signed_distance(const Eigen::Vector3d& p) const;
  // Whether p lies inside the faces by the parity of the faces three skew rays from it cross (the
  // majority of the three; needs a closed mesh); false without faces. The signed distance's side
  // where the nearest face does not tell it.
  bool inside_by_rays(const Eigen::Vector3d& p) const;
  // The least signed distance along the segment [a, b], as a lower bound within
  // max(eps, (floor - truth) / 1000) of the truth wherever the truth is below `floor` (where it is
  // not, the result is only known to be at least min(floor, the least found)): sampled every
  // `step`, and a stretch halved while the bounds on the distance between its ends leave room for
  // less than min(floor, the least found - that precision), 4096 + 64 L / step halvings at most -
  // between two points g apart the distance is at least (d1 + d2 - g) / 2 (1-Lipschitz) and at
  // least min(d1, d2) - g² / (8 d_low) (a minimum of convex functions of curvature at most
  // 1 / d_low, d_low > 0 the first bound; as ../shared/tools/verify_part.py). `where` gets the
  // point of the least distance found, `evaluations` is increased by the distances asked.
  // With is_signed false, the same for the unsigned distance (an open mesh has no inside). Past
  // the halvings (a signed distance that flips without passing zero: a mesh whose inside is
  // ambiguous) the result is still a lower bound, only not that close.
  double least_along(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step, double floor, double eps,
                     Eigen::Vector3d& where, std::size_t& evaluations, bool is_signed = true) const;
  // The least unsigned distance from the segment [a, b] to the faces and points, exact to
  // rounding, and into `where` the point of the segment nearest them (a where no face or point is
  // held): one search of the triangles and points within the segment's half length plus the
  // distance at its middle of that middle, each asked for its nearest pair with the segment
  // (closest_segment_triangle). Pieces longer than the distance at their middle are split first,
  // so a search's sphere stays near the size of one point's. A point that is not finite:
  // std::invalid_argument.
  double least_on_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Vector3d& where) const;
  // How far the ball of radius r centred at c moves along the unit direction d before it touches
  // the faces or points (a drop-cutter along any axis): the least t in [0, max] with them r from
  // c + t d, exact to rounding; max when nothing comes that near on the way; 0 when they are r
  // from c or nearer already. One ray through Embree's boxes of the triangles grown by r (built
  // for each radius when first asked), each asked where the ball first touches it
  // (ball_touch_triangle); the held points as balls of r plus their margin. A c or d that is not
  // finite, r <= 0 or max < 0: std::invalid_argument.
  double touch_along(const Eigen::Vector3d& c, const Eigen::Vector3d& d, double r, double max) const;
  // Whether every point of the segment [a, b] is at least `floor` from the faces and points
  // (unsigned): least_along's test, answered sooner. Marched from a by at least `step`, farther
  // where the distance leaves room (1-Lipschitz: nothing within d - floor of a point d away comes
  // nearer than floor), each stretch halved under least_along's bounds until they clear it, and
  // false at the first distance under it. Conservative: past 4096 + 64 L / step halvings, or a
  // stretch shorter than 1e-6 mm not yet cleared, false. `evaluations` counts the distances asked.
  bool clear_along(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step, double floor,
                   std::size_t* evaluations = nullptr) const;

 private:
  struct Impl;
  struct HeldPoints;
  MeshDistance() = default;
  Eigen::Vector3d to_mesh(const Eigen::Vector3d& p) const { return placed_ ? Eigen::Vector3d(rotation_.transpose() * (p - translation_)) : p; }
  Eigen::Vector3d from_mesh(const Eigen::Vector3d& p) const { return placed_ ? Eigen::Vector3d(rotation_ * p + translation_) : p; }
  double unsigned_in_mesh(const Eigen::Vector3d& p) const;  // p in the mesh's own frame
  double signed_in_mesh(const Eigen::Vector3d& p) const;
  double faces_unsigned(const Eigen::Vector3d& p) const;  // the faces alone, the mesh's frame
  // The faces' nearest point to p and its triangle (the mesh's frame), looked for within
  // `radius` first (the distance to a point known on them), then everywhere. Needs faces.
  Eigen::Vector3d foot_in_mesh(const Eigen::Vector3d& p, double radius, std::size_t& tri) const;
  // unsigned_in_mesh, the faces' search started from `near` (a point on them near p, when
  // has_near), which then gets p's nearest point on them: along a segment the searches are near.
  double unsigned_near(const Eigen::Vector3d& p, Eigen::Vector3d& near, bool& has_near) const;
  double faces_signed(const Eigen::Vector3d& p) const;
  bool inside_in_mesh(const Eigen::Vector3d& p) const;  // inside_by_rays, p in the mesh's frame
  double to_held_points(const Eigen::Vector3d& p) const;  // the least over the held sets; +infinity without them
  // least_on_segment in the mesh's frame, for a segment whose middle is `distance` from the faces
  // and points: lowers `least` and moves `where` where the segment comes nearer.
  void least_on_piece(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double distance, double& least,
                      Eigen::Vector3d& where) const;
  std::shared_ptr<Impl> impl_;
  std::vector<std::shared_ptr<const HeldPoints>> held_;  // each set with its margin
  bool placed_ = false;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_ = Eigen::Vector3d::Zero();
};

// points  #P by 3; mesh  any polygons (each fanned into triangles from its first corner).
// Returns #P unsigned distances to the nearest point of the mesh's faces, computed in parallel;
// all +infinity when the mesh has no face.
std::vector<double> distances_to_mesh(const std::vector<Eigen::Vector3d>& points, const Mesh& mesh);

}  // namespace scallop
