// The nearest point of a triangle to a point, the nearest points of a triangle and a segment, and
// where a moving ball first touches a triangle: the mesh distances' exact step after a search has
// found the triangles that may hold them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

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

// Whether x, a point of the triangle's plane, lies in the triangle (t0, t1, t2) (n its normal
// (t1 - t0) x (t2 - t0), not 0); on an edge counts.
inline bool in_triangle(const Eigen::Vector3d& x, const Eigen::Vector3d& t0, const Eigen::Vector3d& t1,
                        const Eigen::Vector3d& t2, const Eigen::Vector3d& n) {
  return n.dot((t1 - t0).cross(x - t0)) >= 0 && n.dot((t2 - t1).cross(x - t1)) >= 0 && n.dot((t0 - t2).cross(x - t2)) >= 0;
}

// How far along the unit direction d the ball of radius r centred at o moves before it first
// touches the point c (|o + t d - c| = r, the smaller root); +infinity if it passes by or c is
// behind. o must be farther than r from c.
inline double ball_touch_point(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double r, const Eigen::Vector3d& c) {
  const Eigen::Vector3d m = o - c;
  const double b = m.dot(d), disc = b * b - (m.squaredNorm() - r * r);
  const double t = disc >= 0 ? -b - std::sqrt(disc) : -1.0;
  return t >= 0 ? t : std::numeric_limits<double>::infinity();
}

// The nearest points of the segment [a, b] and the triangle (t0, t1, t2): on_segment and
// on_triangle; returns their squared distance (0 where the segment crosses the triangle). Apart,
// the nearest pair has an end of the segment or a point of an edge of the triangle in it (two
// convex sets: a pair inside both needs the segment parallel to the plane, and sliding along it
// keeps the distance until one of those), so it is the nearest of the ends' nearest points and
// the segment's against each edge.
inline double closest_segment_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& t0,
                                       const Eigen::Vector3d& t1, const Eigen::Vector3d& t2, Eigen::Vector3d& on_segment,
                                       Eigen::Vector3d& on_triangle) {
  const Eigen::Vector3d n = (t1 - t0).cross(t2 - t0);
  const double da = n.dot(a - t0), db = n.dot(b - t0);
  if (n.squaredNorm() > 0 && ((da <= 0 && db >= 0) || (da >= 0 && db <= 0)) && da != db) {
    // Where the segment meets the plane, inside the triangle: they cross.
    const Eigen::Vector3d x = a + (da / (da - db)) * (b - a);
    if (in_triangle(x, t0, t1, t2, n)) {
      on_segment = on_triangle = x;
      return 0;
    }
  }
  on_segment = a, on_triangle = closest_on_triangle(a, t0, t1, t2);
  double best = (on_triangle - a).squaredNorm();
  const Eigen::Vector3d at_b = closest_on_triangle(b, t0, t1, t2);
  if (const double d = (at_b - b).squaredNorm(); d < best) best = d, on_segment = b, on_triangle = at_b;
  Eigen::Vector3d cs, ct;
  for (const auto& [p, q] : {std::pair{&t0, &t1}, std::pair{&t1, &t2}, std::pair{&t2, &t0}})
    if (const double d = closest_between_segments(a, b, *p, *q, cs, ct); d < best) best = d, on_segment = cs, on_triangle = ct;
  return best;
}

// How far along the unit direction d the ball of radius r centred at o moves before it first
// touches the triangle (t0, t1, t2): the least t >= 0 where the triangle comes within r of
// o + t d; +infinity if it never does. o must be farther than r from the triangle. The points
// within r of a triangle are the union of balls about its corners, cylinders about its edges and
// the slab of the face between its planes moved r either way (where a slab's side is reached, an
// edge's cylinder holds it), so the first touch is the earliest entry into one of those seven.
inline double ball_touch_triangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double r, const Eigen::Vector3d& t0,
                                  const Eigen::Vector3d& t1, const Eigen::Vector3d& t2) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d* c : {&t0, &t1, &t2}) best = std::min(best, ball_touch_point(o, d, r, *c));
  for (const auto& [p, q] : {std::pair{&t0, &t1}, std::pair{&t1, &t2}, std::pair{&t2, &t0}}) {
    // the distance from the edge's line, for the part of the edge between its ends
    const Eigen::Vector3d e = *q - *p;
    const double ee = e.squaredNorm();
    if (!(ee > 0)) continue;
    const Eigen::Vector3d m = o - *p, dp = d - (d.dot(e) / ee) * e, mp = m - (m.dot(e) / ee) * e;
    const double a = dp.squaredNorm();
    if (!(a > 1e-18)) continue;  // moving along the edge: its ends' balls come first
    const double b = mp.dot(dp), disc = b * b - a * (mp.squaredNorm() - r * r);
    if (disc < 0) continue;
    const double t = (-b - std::sqrt(disc)) / a;
    const double s = (m + t * d).dot(e) / ee;
    if (t >= 0 && s >= 0 && s <= 1) best = std::min(best, t);
  }
  const Eigen::Vector3d n = (t1 - t0).cross(t2 - t0);
  const double nn = n.norm();
  if (nn > 0) {
    const Eigen::Vector3d u = n / nn;
    const double towards = u.dot(d);
    if (towards != 0)
      for (double side : {-1.0, 1.0}) {
        const double t = (side * r - u.dot(o - t0)) / towards;
        if (!(t >= 0 && t < best)) continue;
        const Eigen::Vector3d x = o + t * d - side * r * u;  // on the face's plane
        if (in_triangle(x, t0, t1, t2, n)) best = t;
      }
  }
  return best;
}

}  // namespace scallop
