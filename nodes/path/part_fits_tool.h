// Is the part at least as wide as the ball that is to finish it?
//
// A part narrower than the ball is no finishing job: the planner would still "plan" it, with
// moves many times wider than the part, and the certificate would pass. Nearly always the cloud
// is in metres (a 100 mm part read as 0.1 mm), so the message says which scale to set.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace scallop {

// P  #P positions (mm), finite;  tool_radius  r (mm) > 0.
// The part's width is the larger side of the xy bounding box of P. Returns "" when it is at
// least the ball's diameter 2r, else the refusal, e.g.
//   "the part is 0.1 mm wide, smaller than the 8 mm ball (tool_radius 4 mm): is the cloud in
//    metres? set the reader's scale to 1000 (--set read.scale=1000 with the shipped graphs), or
//    use a smaller tool"
// (the suggestion of a scale only for a part that, 1000 times larger, would be at least as wide
// as the ball and at most 10 m wide).
std::string part_narrower_than_ball(const std::vector<Eigen::Vector3d>& P, double tool_radius);

}  // namespace scallop
