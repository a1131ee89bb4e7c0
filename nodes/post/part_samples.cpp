#include "nodes/post/part_samples.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace scallop {

std::vector<PartTriangle> part_triangles(const Mesh& m) {
  std::vector<PartTriangle> out;
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k) {
      PartTriangle t{m.vertices[m.face(f)[0]], m.vertices[m.face(f)[k]], m.vertices[m.face(f)[k + 1]], {},
                     std::uint32_t(f), {m.face(f)[0], m.face(f)[k], m.face(f)[k + 1]}};
      const Eigen::Vector3d n = (t.b - t.a).cross(t.c - t.a);
      if (!(n.norm() > 0)) continue;  // a degenerate triangle stands for no area
      t.n = n.normalized();
      out.push_back(t);
    }
  return out;
}

namespace {

// The triangle as its longest edge (from `from`, along `edge`, length L) and the apex.
struct Strips {
  Eigen::Vector3d from, to, apex;
  double length, height;
};

Strips strips_of(const PartTriangle& t) {
  const Eigen::Vector3d v[3] = {t.a, t.b, t.c};
  int k = 0;
  double longest = -1;
  for (int e = 0; e < 3; ++e)
    if (const double l = (v[(e + 1) % 3] - v[e]).norm(); l > longest) longest = l, k = e;
  const Eigen::Vector3d& p0 = v[k];
  const Eigen::Vector3d& p1 = v[(k + 1) % 3];
  const Eigen::Vector3d& q = v[(k + 2) % 3];
  return {p0, p1, q, longest, (p1 - p0).cross(q - p0).norm() / longest};
}

int strip_count(const Strips& s, double spacing) {
  return std::max(1, static_cast<int>(std::ceil(s.height / spacing)));
}

// Points on strip i's mid-line: the width there over the spacing, at least one.
int strip_points(const Strips& s, int strips, int i, double spacing) {
  const double t = (i + 0.5) / strips;
  return std::max(1, static_cast<int>(std::ceil(s.length * (1 - t) / spacing)));
}

}  // namespace

std::size_t part_sample_count(const std::vector<PartTriangle>& tris, double spacing) {
  std::size_t c = 0;
  for (const PartTriangle& t : tris) {
    const Strips s = strips_of(t);
    const int k = strip_count(s, spacing);
    for (int i = 0; i < k; ++i) c += std::size_t(strip_points(s, k, i, spacing));
  }
  return c;
}

double part_sample_spacing(const std::vector<PartTriangle>& tris, double spacing, std::size_t max_samples) {
  for (int it = 0; it < 40 && part_sample_count(tris, spacing) > max_samples; ++it) spacing *= 1.15;
  return spacing;
}

std::vector<PartSample> sample_part(const std::vector<PartTriangle>& tris, double spacing) {
  std::vector<PartSample> out;
  out.reserve(part_sample_count(tris, spacing));
  for (std::size_t index = 0; index < tris.size(); ++index) {
    const PartTriangle& t = tris[index];
    const Strips s = strips_of(t);
    const double area = 0.5 * (t.b - t.a).cross(t.c - t.a).norm();
    const int k = strip_count(s, spacing);
    for (int i = 0; i < k; ++i) {
      // The strip between heights i / k and (i + 1) / k of the way to the apex, its area a
      // difference of the similar triangles above its two sides.
      const double t0 = double(i) / k, t1 = double(i + 1) / k, tm = (i + 0.5) / k;
      const double strip_area = area * ((1 - t0) * (1 - t0) - (1 - t1) * (1 - t1));
      const Eigen::Vector3d m0 = s.from + tm * (s.apex - s.from), m1 = s.to + tm * (s.apex - s.to);
      const int m = strip_points(s, k, i, spacing);
      for (int j = 0; j < m; ++j)
        out.push_back({m0 + (j + 0.5) / m * (m1 - m0), strip_area / m, std::uint32_t(index)});
    }
  }
  return out;
}

bool in_part_triangle(const PartTriangle& t, const Eigen::Vector3d& p) {
  const Eigen::Vector3d e[3] = {t.b - t.a, t.c - t.b, t.a - t.c}, v[3] = {t.a, t.b, t.c};
  for (int k = 0; k < 3; ++k)
    if (e[k].cross(p - v[k]).dot(t.n) < 0) return false;
  return true;
}

Eigen::Vector3d same_place(const PartTriangle& t, const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& V) {
  const Eigen::Vector3d e1 = t.b - t.a, e2 = t.c - t.a, q = p - t.a;
  const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), q1 = q.dot(e1), q2 = q.dot(e2);
  const double det = d11 * d22 - d12 * d12;
  const double u = (d22 * q1 - d12 * q2) / det, v = (d11 * q2 - d12 * q1) / det;
  return (1 - u - v) * V[t.corner[0]] + u * V[t.corner[1]] + v * V[t.corner[2]];
}

double ball_clearance(const MeshDistance& part, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius,
                      double tolerance) {
  // The sample itself is within `radius` of the centre: the search starts from it.
  return part(p + radius * n, p) - (radius - tolerance);
}

bool ball_reaches(const MeshDistance& part, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius,
                  double tolerance) {
  return ball_clearance(part, p, n, radius, tolerance) >= 0;
}

}  // namespace scallop
