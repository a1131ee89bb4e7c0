// The workpiece's setup base found and removed (mesh.setup_base).
//
// papers/point-clouds-to-workpieces.md, "Removal of workpiece setup base": the part is machined
// on its base first and then clamped on it, so the base is cut away from the mesh before the
// segmentation. The paper clusters the faces' outward unit normals by K-means and takes the
// cluster of the best objective
//     epsilon = mu * S + gamma * Gamma   (mu = 0.7, gamma = 0.3)
// with S the cluster's similarity and Gamma its quantity, which it does not define further.
// Here, for a cluster C of faces with areas a_f and unit normals n_f (A = sum of a_f):
//   m      = sum a_f n_f / A, its mean normal; the centre's direction d = m / |m|
//   S      = sum a_f (n_f . d) / A = |m|: the area-weighted mean cosine to the mean direction,
//            1 for a flat cluster, smaller the more its normals spread, in [0, 1]
//   Gamma  = A / (the largest cluster's A), in (0, 1], 1 for the largest cluster. Normalised to
//            the largest rather than taken as the area fraction because the fractions of k = 6
//            clusters are mostly below 0.3, so gamma * fraction would weigh under 0.1 and a tiny
//            flat cluster would nearly always win; normalised, S and Gamma span the same range
//            and mu, gamma weigh them as written.
// K-means is weighted by the face areas (kmeans in nodes/geom/kmeans.h): a CAD triangulation
// has a few large triangles on a flat face and many small ones on a fillet, and counting faces
// would make the fillet the "large" cluster. On an even quad mesh the two agree.
//
// What the paper leaves implicit is made explicit and safe. The cluster only gives a direction;
// what is removed is the base's flat part: the faces whose normal lies within flat_angle of the
// base direction d AND whose every corner lies on the part's extreme plane along d (within
// plane_tolerance of the largest v . d over all vertices), and of those the connected group
// (faces joined by shared edges) of the largest area. A face elsewhere with the same normal (the
// underside of an overhang, a second face at another height) is never removed: such faces are
// counted in the result. A cluster's mean normal d may lean off its flat face by more than
// flat_angle (the fandisk's back face shares its cluster with the fillets beside it: measured,
// no flat part found), so the flat part is sought along the cluster's flattest direction: the
// normal of its faces around which most of its area lies within flat_angle (tried from at most
// 256 of its faces), averaged over those faces. The plane tolerance is generous (1 % of the
// diagonal) because the plane is that of the most extreme vertex, and a quad mesh's vertices on
// sharp edges overshoot: the fandisk x50 in 3000 quads from QuadriFlow has a rim vertex 0.52 mm
// below its base and base faces with a corner 0.71 mm above that vertex (0.49 % of the
// diagonal); the connectivity, not the tolerance, keeps a step at another height out.
// Clusters are tried in order of their objective; the first whose flat
// part holds at least min_area of the mesh's area is the base (a curved cluster such as a dome
// has no flat part). When none has, the part has no base: an open mesh (a scan of one side,
// resting on what it does not show) is taken whole, direction zero and nothing removed; a closed
// one makes setup_base throw, asking for the direction. With options.direction given, that direction is the base's and its flat part is
// removed, whatever its size (none: nothing is removed, base_faces is empty).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

struct SetupBaseOptions {
  int clusters = 6;               // k of the K-means
  double mu = 0.7;                // weight of the similarity S
  double gamma = 0.3;             // weight of the quantity Gamma
  int seed = 1;                   // of the K-means seeding (deterministic)
  double flat_angle_deg = 5;      // a base face's normal lies within this of the base direction
  double plane_tolerance = 0.01;  // ... and its corners this far from the extreme plane, times the
                                  // bounding box diagonal
  double min_area = 0.02;         // the smallest flat part taken for a base, fraction of the area
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // the base's outward normal; zero: find it
};

// One K-means cluster of the face normals, as rated for the base.
struct BaseCluster {
  Eigen::Vector3d direction;  // unit mean normal d
  std::size_t faces = 0;
  double area = 0;            // mm^2
  double similarity = 0;      // S
  double quantity = 0;        // Gamma
  double objective = 0;       // epsilon
  Eigen::Vector3d flat_direction;  // the cluster's flattest direction (see below)
  double flat_area = 0;       // mm^2 of the flat part along flat_direction (see above)
};

// mesh          the part without its base: the faces not removed, in their order; the vertices
//               still used, renumbered in their order (normals carried); face_label and
//               feature_edges carried (feature edges that are no longer an edge of a face dropped)
// direction     the base's outward unit normal (zero: an open mesh without a base, taken whole):
//               the given one, or the area-weighted mean normal
//               of the removed faces
// base_faces    indices (into the input) of the removed faces, increasing
// base_area     their area, mm^2; area: the whole mesh's
// plane_offset  the extreme plane: v . direction = plane_offset (mm)
// clusters      the K-means clusters, objective best first (empty when the direction was given)
// chosen        index into clusters of the base's cluster (-1 when the direction was given)
// how           how the base was chosen, one sentence
// facing_kept_faces, facing_kept_area  faces whose normal lies within flat_angle of the direction
//               but were kept: off the extreme plane or not joined to the base
struct SetupBaseResult {
  Mesh mesh;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  std::vector<std::uint32_t> base_faces;
  double base_area = 0, area = 0;
  double plane_offset = 0;
  std::vector<BaseCluster> clusters;
  int chosen = -1;
  std::string how;
  std::size_t facing_kept_faces = 0;
  double facing_kept_area = 0;
  std::size_t vertices_removed = 0;
};

// mesh  a polygon mesh (triangles, quads, mixed), faces counter-clockwise seen from outside.
// Throws std::invalid_argument for a mesh without faces of area or bad options, and
// std::runtime_error when no cluster has a flat part of min_area (the message says so and asks
// for the direction) or when the base is the whole mesh.
SetupBaseResult setup_base(const Mesh& mesh, const SetupBaseOptions& options);

// The base direction of mesh.setup_base's report (its base_direction [x, y, z]); throws
// std::invalid_argument when the report has none.
Eigen::Vector3d base_direction_of(const nlohmann::json& report);

}  // namespace scallop
