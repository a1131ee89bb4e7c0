#include "nodes/path/step_size.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace scallop {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Lower root >= 0 of the ray entering the ball (c, r), +infinity if none (o is outside).
double sphere_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& c,
                    double r) {
  const Eigen::Vector3d oc = o - c;
  const double b = d.dot(oc);
  const double disc = b * b - (oc.squaredNorm() - r * r);
  if (disc < 0) return kInf;
  const double t = -b - std::sqrt(disc);
  return t >= 0 ? t : kInf;
}
}  // namespace

FundamentalForms fundamental_forms(const Eigen::Vector3d& ru, const Eigen::Vector3d& rv,
                                   const Eigen::Vector3d& ruu, const Eigen::Vector3d& ruv,
                                   const Eigen::Vector3d& rvv, const Eigen::Vector3d& n) {
  return {ru.dot(ru), ru.dot(rv), rv.dot(rv), n.dot(ruu), n.dot(ruv), n.dot(rvv)};
}

double normal_curvature(const FundamentalForms& f, double du, double dv) {
  const double I = f.E * du * du + 2 * f.F * du * dv + f.G * dv * dv;
  const double II = f.L * du * du + 2 * f.M * du * dv + f.N * dv * dv;
  return -II / I;
}

Eigen::Vector2d principal_curvatures(const FundamentalForms& f) {
  // Shape operator S = -I^-1 II; its eigenvalues are real (I and II symmetric, I > 0).
  Eigen::Matrix2d I, II;
  I << f.E, f.F, f.F, f.G;
  II << f.L, f.M, f.M, f.N;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> es(-II, I, Eigen::EigenvaluesOnly);
  return es.eigenvalues();  // ascending
}

double forward_interval(double chord_error, double curvature) {
  if (!(curvature > 0)) return kInf;
  const double R = 1.0 / curvature;
  if (chord_error >= 2 * R) return 2 * R;
  return std::sqrt(8 * chord_error * R - 4 * chord_error * chord_error);
}

bool ball_cannot_reach(double tool_radius, double kappa) { return 1 + tool_radius * kappa <= 0; }

double side_interval(double scallop_height, double tool_radius, double kappa) {
  if (ball_cannot_reach(tool_radius, kappa)) return kInf;
  // R / (R +- r) = 1 / (1 + r kappa) with the signed curvature; a plane gives sqrt(8 h r).
  return std::sqrt(8 * scallop_height * tool_radius / (1 + tool_radius * kappa));
}

double side_step_conformal(double side_interval, double ru_norm) { return side_interval / ru_norm; }

double side_step_corrected(double side_interval, double ru_norm, double theta) {
  return side_interval / (ru_norm * std::cos(std::abs(theta - M_PI / 2)));
}

double cusp_height_plane(double tool_radius, double spacing) {
  return tool_radius - std::sqrt(tool_radius * tool_radius - spacing * spacing / 4);
}

double ray_capsule_entry(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                         const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r, double before) {
  const Eigen::Vector3d ba = b - a;
  const double baba = ba.squaredNorm();
  // Inside already? Too far to be entered before `before`? (the ray's point at t is within t
  // of o, so it reaches the capsule no sooner than the segment's distance less r)
  {
    const double y = baba > 0 ? std::clamp((o - a).dot(ba) / baba, 0.0, 1.0) : 0.0;
    const double d2 = (o - (a + y * ba)).squaredNorm();
    if (d2 <= r * r) return 0;
    if (before < INFINITY && d2 > (r + before) * (r + before)) return INFINITY;
  }
  // The capsule is the union of the two end balls and the finite cylinder; the first hit of a
  // union is the earliest first hit of its parts.
  double t = std::min(sphere_entry(o, d, a, r), sphere_entry(o, d, b, r));
  if (baba > 0) {
    const Eigen::Vector3d oa = o - a;
    const double bard = ba.dot(d), baoa = ba.dot(oa);
    const double A = baba - bard * bard;
    if (A > 1e-12 * baba) {
      const double B = baba * d.dot(oa) - baoa * bard;
      const double C = baba * oa.squaredNorm() - baoa * baoa - r * r * baba;
      const double disc = B * B - A * C;
      if (disc >= 0) {
        const double tc = (-B - std::sqrt(disc)) / A;
        const double y = baoa + tc * bard;
        if (tc >= 0 && y >= 0 && y <= baba) t = std::min(t, tc);
      }
    }
  }
  return t;
}

}  // namespace scallop
