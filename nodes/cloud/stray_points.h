// Stray points: returns of a scanner that lie off the surface their neighbours sample (spikes,
// flying pixels at depth steps, reflections, dust). They are not noise the denoising averages
// out: a point 0.5 mm above a smooth patch is a spike the gouge guard lifts every ball over, and
// a point under the surface makes the cloud look layered (cloud.height_field_check refuses it).
#pragma once

#include <cstdint>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

// P   #P points (mm); nb  their k nearest neighbours (k >= 8, the point itself excluded).
// Returns #P flags, 1 for a stray point: one farther from the quadric its neighbours sample than
//   max(kStrayNoise × their rms residual from it (at least the median over the cloud),
//       kStraySpacing × the distance to its k-th),
// the quadric fitted by least squares in the frame of their best-fit plane (the point itself left
// out); or one isolated, its k-th neighbour more than kStrayIsolation times as far as the median
// of its neighbours' own k-th (a point in the air beside the patch, whose neighbours' quadric
// extrapolated may pass near it). A smooth patch's points lie on it to their noise; a crest or crease sampled on both sides
// misfits it by a small part of the neighbourhood's radius, as its neighbours along it do (a
// 1 mm crest, 12 000 points on 40 x 30 mm: under 0.05 mm, within 8 of their rms residuals); a
// stray point 0.3 mm off does not, nor, on a clean cloud, one 0.1 mm off.
// A burst of points all within a millimetre of one another samples a surface of its own: not
// stray by this test.
// off  optional: #P distances from that quadric (mm).
std::vector<std::uint8_t> stray_points(const std::vector<Eigen::Vector3d>& P, const Neighborhoods& nb,
                                       std::vector<double>* off = nullptr);

constexpr double kStrayNoise = 8;       // times the neighbours' rms residual
constexpr double kStraySpacing = 0.05;  // times the distance to the k-th neighbour
constexpr double kStrayIsolation = 3;   // times the neighbours' median distance to their k-th

}  // namespace scallop
