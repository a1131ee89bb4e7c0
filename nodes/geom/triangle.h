// The nearest point of a triangle to a point: the mesh distances' exact step after a search has
// found the triangles that may hold it.
#pragma once

#include <Eigen/Core>

#include "nodes/geom/segment.h"

namespace scallop {

// The point of triangle (a, b, c) nearest q, by the region of the triangle's plane q projects
// into (its corners, edges or inside: Ericson, Real-Time Collision Detection, 5.1.5). A triangle
// with no area (its corners on one line, or equal): the nearest of its three edges.
inline Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                           const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, aq = q - a;
  const double d1 = ab.dot(aq), d2 = ac.dot(aq);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bq = q - b;
  const double d3 = ab.dot(bq), d4 = ac.dot(bq);
  if (d3 >= 0 && d4 <= d3) return b;
  const Eigen::Vector3d cq = q - c;
  const double d5 = ab.dot(cq), d6 = ac.dot(cq);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  const double sum = va + vb + vc;  // |ab x ac|^2 where the triangle has area
  if (!(sum > 1e-12 * ab.squaredNorm() * ac.squaredNorm())) {
    Eigen::Vector3d best = closest_on_segment(q, a, b);
    for (const Eigen::Vector3d& p : {closest_on_segment(q, b, c), closest_on_segment(q, c, a)})
      if ((p - q).squaredNorm() < (best - q).squaredNorm()) best = p;
    return best;
  }
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  return a + (vb / sum) * ab + (vc / sum) * ac;
}

}  // namespace scallop
