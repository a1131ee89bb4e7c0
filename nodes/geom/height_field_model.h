// The surface a cloud samples, as a height field z(x, y) seen from +z: what the planner lifts
// the ball on, what the gouge guard checks it against and what the certificate (post.simulate)
// measures against. (Not the node cloud.height_field_check, nodes/cloud/height_field.h, which
// asks whether a cloud is a height field at all.)
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/geom/kd_tree.h"

namespace scallop {

// Height-field model of a cloud seen from +z: z(x, y) and the upward normal from a weighted
// quadratic least-squares fit of the k nearest cloud points in xy; where the surface is steeper
// than ~37 degrees, from a quadratic fitted in the local tangent frame to the k nearest points
// in 3-D (a fit of z over xy is ill-posed there when the points crowd together in xy). Where the
// quadratic misfits its points (a crest, a crease), a quartic over the 2k nearest in its place
// when it fits them better and agrees with it (kQuarticFrom, height_field_model.cpp).
class HeightFieldModel {
 public:
  // P  #P by 3 cloud points (mm), at least 10. k  neighbours per fit.
  // uncertainty  optional #P bounds (mm) on how far each point may be off the real surface
  // The model reads P and uncertainty where they are: both must outlive it (a temporary P is
  // moved in and kept by the model instead).
  HeightFieldModel(const std::vector<Eigen::Vector3d>& P, int k = 20,
                   const std::vector<double>* uncertainty = nullptr);
  HeightFieldModel(std::vector<Eigen::Vector3d>&& P, int k = 20, const std::vector<double>* uncertainty = nullptr);
  ~HeightFieldModel();
  HeightFieldModel(const HeightFieldModel&) = delete;
  HeightFieldModel& operator=(const HeightFieldModel&) = delete;
  // Evaluates at (x, y); false (and nothing evaluated) when (x, y) is outside the patch: no cloud
  // point within 1.5 × the mean cloud spacing, or the fitted neighbours lie to one side (their
  // centroid farther than half their radius from (x, y)), unless `force`.
  // uncertainty, when given, gets how far z may be off the real surface: the neighbours'
  // uncertainties carried through the fit (at least their mean) plus 3 times the fit's misfit
  // (the largest residual beyond a neighbour's own uncertainty: the quadratic's shape bias,
  // all of the error on a clean cloud; for a quartic, its misfit plus a third of its difference
  // from the quadratic), grown at the edge where the nearest point is
  // d > spacing / 2 away (a gap z is extrapolated across): by the factor
  // 1 + (d − spacing / 2) / (2 spacing) beyond the edge, fading to 1 inside it. It is set also
  // when eval returns false for a place outside the patch (the fit there, extrapolated).
  bool eval(double x, double y, double& z, Eigen::Vector3d& normal, bool force = false,
            double* uncertainty = nullptr) const;
  // eval(x, y, z, normal, force = true, &uncertainty) in two steps, for a caller that may not
  // need the uncertainty where it is small: all but the growth beyond the cloud's edge (whose
  // angular test over the 64 nearest points is the costly part at a rim), with the largest
  // growth possible there (1 inside the edge, else 1 + (d − spacing / 2) / (2 spacing), d the
  // nearest point's distance); false where eval is. The uncertainty eval gives is then
  // before_growth × edge_growth(x, y), to the last bit.
  bool eval_before_growth(double x, double y, double& z, Eigen::Vector3d& normal, double& before_growth,
                          double& growth_max) const;
  double edge_growth(double x, double y) const;
  bool inside(double x, double y) const;
  // The foot point of c: the place (x, y) of the field nearest c, looked for from `start` by steps
  // to the projection of c onto the tangent plane (at most max_step long), a step that ends
  // farther from c halved back, down to 1e-4 mm (where the surface curves tighter than its
  // distance from c the projection overshoots, and undamped the search swings off a crest onto
  // its flanks). The field evaluated as eval(force = true) does; false when it cannot be at
  // `start`.
  bool foot_point(const Eigen::Vector3d& c, const Eigen::Vector2d& start, double max_step, Eigen::Vector2d& at) const;
  // How far (x, y) lies beyond the outermost of its 64 nearest points, seen from their centroid
  // (mm; <= 0 among them, e.g. in a gap between the points of a rim).
  double reach_beyond(double x, double y) const;
  // Whether eval's uncertainty may be larger near (x, y) than at it: (x, y) lies beyond the
  // cloud's edge (its nearest point farther than half a spacing and its neighbours leaving a gap
  // wider than 0.6 pi: there the uncertainty grows with the distance from the points), or the fit
  // there misfits its points by more than `misfit_floor` mm (kMisfitFactor times the misfit, as
  // eval counts it: across a crest it changes within a spacing). Elsewhere the uncertainty is
  // the mean of the nearest points' own, which a step of a spacing changes little.
  bool uncertainty_may_grow(double x, double y, double misfit_floor) const;
  // How far the surface at (x, y) may be off the real one (mm), as eval gives it (without
  // per-point uncertainties, the misfit alone).
  double uncertainty(double x, double y) const;
  double uncertainty_max() const { return uncertainty_max_; }
  // The cloud's points as the model reads them, and a 3-D k-d tree over them (leaf size 16; the
  // steep places' fits search it), built on first use, once: other checks over the same points
  // search it too rather than build their own (half a second per million points).
  const std::vector<Eigen::Vector3d>& points() const;
  const KdTree<Eigen::Vector3d, 3>& tree3d() const;
  double spacing() const { return spacing_; }  // mean cloud spacing in xy (mm)
  double min_x() const { return lo_.x(); }
  double min_y() const { return lo_.y(); }
  double max_x() const { return hi_.x(); }
  double max_y() const { return hi_.y(); }
  double max_z() const { return zmax_; }

 private:
  HeightFieldModel(std::vector<Eigen::Vector3d>&& own, const std::vector<Eigen::Vector3d>* given, int k,
                   const std::vector<double>* uncertainty);
  struct Impl;
  Impl* impl_ = nullptr;
  int k_;
  double spacing_ = 0, zmax_ = 0, uncertainty_max_ = 0;
  Eigen::Vector2d lo_, hi_;
};

}  // namespace scallop
