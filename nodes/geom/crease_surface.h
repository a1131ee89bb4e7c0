// Two planes meeting in a line, fit to a few points: the surface of a part near a crease softer
// than the mesh's feature edges (a CAD mesh's facets meet at 1 to 50 degrees). A quadric through
// points on both facets misses them by about the turn times their spread (0.01 mm on the fandisk's
// 200 000-point cloud); the two planes do not. Used by mesh.cloud_envelope beside LocalSurface.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <utility>
#include <vector>

namespace scallop {

// A ridge (the part below both planes along `up`: its surface the lower of their heights) or a
// valley (the higher). One plane counts as both when the points lie on one.
struct CreaseSurface {
  std::array<Eigen::Vector3d, 2> normal;  // unit, normal[i]·up > 0
  std::array<double, 2> offset;           // plane i: normal[i]·x = offset[i]
  Eigen::Vector3d up;                     // unit: the direction heights are measured along
  bool ridge = true;
  double misfit = 0;  // the points' largest height off the surface, along up (mm)
  // How far each plane stands above x along up (negative: below).
  std::array<double, 2> plane_heights(const Eigen::Vector3d& x) const;
  // How far the surface stands above x along up: the lower of the planes' for a ridge, the higher
  // for a valley.
  double height(const Eigen::Vector3d& x) const;
  // The most it stands above (first) and below (second, positive) the triangle abc: exact, from
  // the corners and the places the crease's line crosses the edges (either side of the line the
  // height is affine in x, so its extremes lie at those places).
  std::pair<double, double> extremes_over(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) const;
};

// The crease surface of `points` seen along `up`: the crease's line first taken along the cross
// product of two seed normals (e.g. of two faces of a mesh at the largest angle around a place),
// the points split across it where the least-squares planes of the two sides miss them least
// (every split tried), then again along the line the two planes found meet in; the ridge or the
// valley, whichever misses the points less. One plane through all the points where no split
// fits better (or the seeds are parallel). nullopt with fewer than 3 points, points along a line,
// or a plane turned more than 60 degrees from up (its heights along up would not bound its
// distances).
std::optional<CreaseSurface> fit_crease_surface(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& up,
                                                const std::array<Eigen::Vector3d, 2>& seed_normal);

}  // namespace scallop
