// Surface reconstruction: a point cloud -> a triangle mesh (CGAL inside the .cpp only).
//
// advancing_front  CGAL's advancing-front surface reconstruction (Cohen-Steiner & Da 2004): the
//                  mesh interpolates the points (every vertex is an input point), so sharp edges
//                  sampled by the cloud stay sharp. On noisy clouds, CGAL's sharpness-aware
//                  bilateral_smooth_point_set (Huang et al. 2013, "Edge-aware point set
//                  resampling") first moves the points (smooth_iterations > 0; needs normals).
//                  The front runs as a process of its own, scallop-advancing-front beside the
//                  running program (helpers/advancing_front_main.cpp), so that its ties fall the
//                  same way whatever this process did before: the same cloud, the same mesh.
// poisson          CGAL's Poisson reconstruction (Kazhdan et al. 2006): watertight, but it rounds
//                  sharp edges and invents surface where there are no points, so faces farther than
//                  trim_spacings average spacings from every point are removed. Needs normals
//                  oriented consistently over the whole cloud.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "nodes/types/mesh.h"

namespace scallop {

enum class ReconstructMethod { advancing_front, poisson };

struct ReconstructOptions {
  ReconstructMethod method = ReconstructMethod::advancing_front;
  int smooth_iterations = 0;      // bilateral passes before advancing front (0: none)
  int smooth_neighbors = 24;      // neighbours of each bilateral fit
  double sharpness_angle = 25.0;  // degrees: bilateral's edge sensitivity (smaller: sharper)
  double radius_ratio_bound = 5.0;  // advancing front: candidate triangles' radius ratio limit
  double beta = 0.52;               // advancing front: half-angle (radians) of the wedge
  double trim_spacings = 3.0;       // poisson: faces farther from the cloud than this are removed
  double poisson_approximation = 0.375;  // poisson: the mesher's distance bound to the implicit surface (spacings)
};

// What the reconstruction did and how close the mesh stays to the input points.
struct ReconstructResult {
  Mesh mesh;                    // triangles, each component oriented like the input normals
  double spacing = 0;           // mean distance from a point to its 6 nearest (mm)
  double smooth_moved = 0;      // bilateral: mean movement of its last pass (mm), 0 when off
  std::size_t trimmed_faces = 0;  // poisson: faces removed far from the points
  std::size_t unused_points = 0;  // input points on no face (advancing front)
  // Distance from every input point to the mesh (mm).
  double distance_mean = 0, distance_p99 = 0, distance_max = 0;
};

// P  #P by 3 points (finite);  N  #P unit normals or empty (required by poisson and by
// smoothing). Throws std::invalid_argument with a message for the user: too few points ("the
// cloud has 3 points; reconstruction needs at least 10"), points all on a line or a plane for
// poisson, normals missing or not consistently oriented for poisson (with how to fix it).
ReconstructResult reconstruct_surface(const std::vector<Eigen::Vector3d>& P,
                                      const std::vector<Eigen::Vector3d>& N,
                                      const ReconstructOptions& options,
                                      const std::function<void(double, const std::string&)>& progress = {});

// Of each point's k nearest neighbours, the share whose normal points the other way
// (negative dot product), averaged over the cloud: about 0 when the normals are consistently
// oriented, 0.5 when they are oriented at random.
double normal_disagreement(const std::vector<Eigen::Vector3d>& P,
                           const std::vector<Eigen::Vector3d>& N, int k = 8);

}  // namespace scallop
