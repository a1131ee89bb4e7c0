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

int part_subdivisions(const PartTriangle& t, double spacing) {
  const double longest = std::max({(t.b - t.a).norm(), (t.c - t.b).norm(), (t.a - t.c).norm()});
  return std::max(1, static_cast<int>(std::ceil(longest / (1.5 * spacing))));
}

std::size_t part_sample_count(const std::vector<PartTriangle>& tris, double spacing) {
  std::size_t c = 0;
  for (const PartTriangle& t : tris) c += std::size_t(part_subdivisions(t, spacing)) * part_subdivisions(t, spacing);
  return c;
}

double part_sample_spacing(const std::vector<PartTriangle>& tris, double spacing, std::size_t max_samples) {
  for (int it = 0; it < 40 && part_sample_count(tris, spacing) > max_samples; ++it) spacing *= 1.15;
  return spacing;
}

std::vector<PartSample> sample_part(const std::vector<PartTriangle>& tris, double spacing) {
  std::vector<PartSample> out;
  out.reserve(part_sample_count(tris, spacing));
  for (std::size_t i = 0; i < tris.size(); ++i) {
    // n² centroids of the triangle cut into n² equal ones, each standing for 1/n² of its area.
    const PartTriangle& t = tris[i];
    const int n = part_subdivisions(t, spacing);
    const double w = 0.5 * (t.b - t.a).cross(t.c - t.a).norm() / (double(n) * n);
    const Eigen::Vector3d du = (t.b - t.a) / n, dv = (t.c - t.a) / n;
    for (int a = 0; a < n; ++a)
      for (int b = 0; a + b < n; ++b) {
        out.push_back({t.a + (a + 1.0 / 3) * du + (b + 1.0 / 3) * dv, w, std::uint32_t(i)});
        if (a + b + 1 < n) out.push_back({t.a + (a + 2.0 / 3) * du + (b + 2.0 / 3) * dv, w, std::uint32_t(i)});
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

bool ball_reaches(const MeshDistance& part, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double radius,
                  double tolerance) {
  // The sample itself is within `radius` of the centre: the search starts from it.
  return part(p + radius * n, p) >= radius - tolerance;
}

}  // namespace scallop
