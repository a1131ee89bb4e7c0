// The points of a part that are not machined and that a ball finishing the rest must keep clear
// of (path.gouge_guard, post.link and post.simulate: cloud.trim_steep's left_out).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nodes/geom/height_field_model.h"

namespace scallop {

// left_out  #L points not machined (mm); patch  the height field of the machined points.
// Returns, in their order, the points of left_out farther than apart = 3 spacings of the patch
// (HeightFieldModel::spacing) from every
// machined point that stand above the patch, where the ball comes from: higher than the nearest
// machined point and every one within 2 apart of them by more than a tenth of its distance
// (6 degrees). A wall
// beside a floor stands well above it. What is nearer, or lower, continues the patch's surface
// past where the trim cut it off (a convex rim, which falls away from a ball touching the patch,
// the patch rising beside it) or lies within its noise; as obstacles such points made the ball
// "reach into" the very surface it finishes (the clean steep cap: 2.2 % of it "not reachable"
// and its rim left 0.115 mm high; the noisy one: its gouge bound 0.0103 > e, from one point the
// trim left inside a ragged kept rim, higher than the kept point nearest it). (Not the fits'
// normals at the patch's edge: beside a wall they point either way.)
std::vector<Eigen::Vector3d> obstacle_points(const std::vector<Eigen::Vector3d>& left_out,
                                             const HeightFieldModel& patch);

// How near a ball of radius r may come to an obstacle point (mm): r and half the patch's spacing
// (no field is fitted to the obstacles; between their samples a sharp edge, a wall's top, can
// stand that much nearer the ball than they do: without it a ball cut 0.043 mm into a 3 mm
// wall's top edge).
inline double obstacle_keep_off(double r, double spacing) { return r + 0.5 * spacing; }

}  // namespace scallop
