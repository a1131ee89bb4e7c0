// Is a cloud one patch that a 3-axis machine can finish from above (tool axis +Z)?
//
// scallop plans ball-end paths over ONE open height-field patch z(x, y). Three things break that
// and would otherwise give a silent wrong path or a confusing error far downstream:
//  - several separate parts (connected components of the k-nearest-neighbour graph);
//  - overlapping layers seen from +Z (a closed object, an overhang, a fold): points with another
//    point of the cloud above them, so the cutter cannot reach them;
//  - walls steeper than the cutter can finish from above.
// analyze_height_field() measures all three; height_field_problem() turns the measurements and
// the limits into a clear message (or none).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nodes/cloud/principal_extents.h"
#include "nodes/types/cloud.h"

namespace scallop {

struct HeightFieldLimits {
  int min_points = 100;                  // fewer points cannot describe a patch to machine
  int max_components = 1;                // significant parts allowed
  double min_component_fraction = 0.01;  // smaller parts are specks: reported, not counted
  double layer_gap = 4.0;                // layers closer than this many spacings are not told apart
  double max_layered_fraction = 0.002;   // share of points under other points that is tolerated
  double max_slope_deg = 85.0;           // steeper points count as steep walls
  double max_steep_fraction = 0.05;      // share of steep points that is tolerated
};

struct HeightFieldStats {
  std::size_t points = 0;
  double spacing = 0;  // median distance to the nearest neighbour (mm)
  PrincipalExtents extents;  // length, width, thickness along the principal axes (mm)
  int k = 0;           // neighbours per point of the graph used
  // Components of the symmetric k-nearest-neighbour graph, largest first.
  std::vector<std::size_t> component_sizes;
  std::vector<int> component;  // #P label of each point (index into component_sizes)
  std::vector<Eigen::Vector3d> component_centroids;  // of the (at most 10) largest components
  int significant_components = 0;  // with at least min_component_fraction of the points
  std::size_t speck_points = 0;    // points in the other components (ignored below)
  // Points (outside specks) that have a point of another layer above them in xy.
  std::size_t layered_points = 0;
  std::vector<char> under;  // #P: 1 where the point lies under another layer
  Eigen::Vector3d layered_example = Eigen::Vector3d::Zero();  // the clearest such point
  double layered_example_gap = 0;  // its distance to the layer above (mm)
  // Slopes (angle of the surface to the xy plane, from |n_z|), outside specks.
  double max_slope_deg = 0;
  Eigen::Vector3d steepest = Eigen::Vector3d::Zero();
  std::size_t steep_points = 0;  // slope above limits.max_slope_deg
  Eigen::Vector2d xy_min = Eigen::Vector2d::Zero(), xy_max = Eigen::Vector2d::Zero();
  double z_min = 0, z_max = 0;
};

// P  #P by 3 positions (mm), all finite;  N  #P by 3 unit normals, oriented or not (only |n_z|
// and the tangent planes are used);  nbrs  k nearest neighbours of every point (cloud.knn).
// Spacing h = median nearest-neighbour distance. Points i, j (j higher) count as different
// layers when (1) they are within 2h of each other in xy, (2) each lies farther than
// layer_gap * h from the other's tangent plane, and (3) no point of the cloud lies within 2h of
// their midpoint. Points of one smooth sheet lie (up to curvature) in each other's tangent
// planes, so a steep or vertical wall (tangent plane containing the z axis) is not a stack;
// (3) keeps the corners of a vertical wall, whose PCA normals are blurred, from counting: the
// wall fills the space between them, while stacked sheets have a gap. The lower point of such a
// pair "lies under" the cloud. Parts smaller than min_component_fraction are left out of the
// layer and slope measurements. Sheets closer than layer_gap * h (thin plates) are not told
// apart.
// Throws std::invalid_argument for mismatched sizes, missing normals, non-finite values, or an
// empty cloud.
HeightFieldStats analyze_height_field(const std::vector<Eigen::Vector3d>& P,
                                      const std::vector<Eigen::Vector3d>& N,
                                      const Neighborhoods& nbrs,
                                      const HeightFieldLimits& limits = {});

// Components of the symmetric k-nearest-neighbour graph (i ~ j if either lists the other).
// Returns the label of every point; labels are numbered by decreasing size (ties: smallest
// point index first), sizes[c] is the number of points labelled c.
std::vector<int> knn_components(const Neighborhoods& nbrs, std::vector<std::size_t>& sizes);

// The first problem found, in the order points, components, layers, slopes, as a message for
// the user; empty when the cloud is one machinable patch within the limits.
std::string height_field_problem(const HeightFieldStats& s, const HeightFieldLimits& limits);

// The measurements as a JSON report (no per-point labels).
nlohmann::json to_json(const HeightFieldStats& s, const HeightFieldLimits& limits);

}  // namespace scallop
