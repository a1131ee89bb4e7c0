#include "nodes/mesh/tgv_normal_filter.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace scallop {
namespace {

using Vec = Eigen::Vector3d;
using Mat = Eigen::Matrix3d;

constexpr std::size_t kGrain = 4096;
constexpr std::uint32_t kNone = 0xffffffffu;

template <class Body>
void for_each(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) body(i);
  });
}

// Runs body(i) for i < n in parallel and sums what it returns (a Vec of up to three sums).
template <class Body>
Vec sum_each(std::size_t n, const Body& body) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), Vec(Vec::Zero()),
      [&](const auto& range, Vec s) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) s += body(i);
        return s;
      },
      [](const Vec& a, const Vec& b) { return Vec(a + b); });
}

template <class T>
double dot(const T& a, const T& b) {
  return a.cwiseProduct(b).sum();
}

// One side of an interior edge as a face sees it.
struct Side {
  std::uint32_t g = kNone;  // the face across (kNone: a boundary edge, no term)
  std::uint32_t e = kNone;  // the interior edge
  double s = 0;             // +1 when the face is the edge's first face, -1 when its second
  double l = 0;             // edge length
  Vec d = Vec::Zero();      // c_face - c_g
};

// The mesh in units of its mean edge length: each interior edge's two faces (the first face
// orients its differences) and length, each face's area and three sides.
struct Layout {
  std::vector<std::array<std::uint32_t, 2>> faces;  // per interior edge
  std::vector<double> l;                            // per interior edge
  std::vector<Vec> d;                               // per interior edge: c_first - c_second
  std::vector<double> a;                            // per face
  std::vector<std::array<Side, 3>> side;            // per face
};

Layout make_layout(const Mesh& mesh, const MeshEdges& edges, const FaceGeometry& geometry) {
  Layout L;
  const std::size_t F = mesh.num_faces();
  std::vector<std::uint32_t> interior(edges.size(), kNone);
  double sum = 0;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.faces_on(e) == 2) {
      interior[e] = static_cast<std::uint32_t>(L.faces.size());
      L.faces.push_back({edges.faces(e)[0], edges.faces(e)[1]});
      const double len = (mesh.vertices[edges.edges[e][0]] - mesh.vertices[edges.edges[e][1]]).norm();
      L.l.push_back(len);
      sum += len;
    }
  const double h = !L.l.empty() && sum > 0 ? sum / static_cast<double>(L.l.size()) : 1.0;
  for (double& len : L.l) len /= h;
  L.d.resize(L.faces.size());
  for_each(L.faces.size(), [&](std::size_t e) {
    L.d[e] = (geometry.centroid[L.faces[e][0]] - geometry.centroid[L.faces[e][1]]) / h;
  });
  L.a.resize(F);
  L.side.resize(F);
  for_each(F, [&](std::size_t f) {
    L.a[f] = geometry.area[f] / (h * h);
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t e = interior[edges.face_edge[mesh.face_start[f] + c]];
      if (e == kNone) continue;
      Side& s = L.side[f][c];
      s.e = e;
      s.s = L.faces[e][0] == f ? 1.0 : -1.0;
      s.g = L.faces[e][0] == f ? L.faces[e][1] : L.faces[e][0];
      s.l = L.l[e];
      s.d = s.s * L.d[e];
    }
  });
  return L;
}

// Preconditioned conjugate gradients on a vector of blocks (Vec or Mat), warm-started from x;
// apply(i, v) is row block i of the matrix times v, precondition(i, r) the preconditioner's
// block i applied to r_i. The passes over the data are fused, four per step. Returns the steps.
template <class T>
struct Pcg {
  std::vector<T> r, z, p, q;

  template <class Apply, class Precondition>
  int solve(std::vector<T>& x, const std::vector<T>& b, const Apply& apply, const Precondition& precondition,
            int max_steps, double tolerance) {
    const std::size_t n = x.size();
    r.resize(n), z.resize(n), p.resize(n), q.resize(n);
    // r = b - A x, z = p = M r; sums r.z, r.r, b.b.
    Vec s = sum_each(n, [&](std::size_t i) {
      r[i] = b[i] - apply(i, x);
      z[i] = precondition(i, r[i]);
      p[i] = z[i];
      return Vec(dot(r[i], z[i]), dot(r[i], r[i]), dot(b[i], b[i]));
    });
    double rz = s[0];
    const double limit = tolerance * tolerance * s[2];
    if (s[2] == 0 || s[1] <= limit) return 0;
    int step = 0;
    while (step < max_steps) {
      ++step;
      const double pq = sum_each(n, [&](std::size_t i) {
        q[i] = apply(i, p);
        return Vec(dot(p[i], q[i]), 0, 0);
      })[0];
      if (!(pq > 0)) break;
      const double alpha = rz / pq;
      s = sum_each(n, [&](std::size_t i) {
        x[i] += alpha * p[i];
        r[i] -= alpha * q[i];
        z[i] = precondition(i, r[i]);
        return Vec(dot(r[i], z[i]), dot(r[i], r[i]), 0);
      });
      if (s[1] <= limit) break;
      const double beta = s[0] / rz;
      rz = s[0];
      for_each(n, [&](std::size_t i) { p[i] = z[i] + beta * p[i]; });
    }
    return step;
  }
};

// The angle (degrees) between two unit vectors |a - b| = chord apart.
double chord_to_deg(double chord) { return 2 * std::asin(std::min(1.0, chord / 2)) * 180 / std::numbers::pi; }

template <class T>
T shrink(const T& v, double t) {
  const double len = v.norm();
  return len > t ? T(v * (1 - t / len)) : T(T::Zero());
}

}  // namespace

TgvResult tgv_filter_normals(const Mesh& mesh, const MeshEdges& edges, const FaceGeometry& geometry,
                             const TgvOptions& o, const std::function<void(double)>& progress) {
  if (!(o.alpha1 > 0) || !std::isfinite(o.alpha1)) throw std::invalid_argument("alpha1 must be positive");
  if (!(o.alpha_ratio > 0) || !std::isfinite(o.alpha_ratio)) throw std::invalid_argument("alpha_ratio must be positive");
  if (!(o.penalty >= 0) || !std::isfinite(o.penalty)) throw std::invalid_argument("penalty must not be negative");
  if (o.iterations < 0) throw std::invalid_argument("iterations must not be negative");
  if (o.cg_iterations < 1 || o.w_cg_iterations < 1) throw std::invalid_argument("cg_iterations must be at least 1");
  if (!(o.tolerance >= 0)) throw std::invalid_argument("tolerance must not be negative");
  if (!mesh.all_triangles()) throw std::invalid_argument("the mesh has faces that are not triangles");
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (!edges.is_manifold(e)) throw std::invalid_argument("the mesh has edges with 3 or more faces");

  const Layout L = make_layout(mesh, edges, geometry);
  const std::size_t F = mesh.num_faces(), E = L.faces.size();
  const double r = o.penalty > 0 ? o.penalty : kAutoPenalty * o.alpha1;
  const double alpha1 = o.alpha1, alpha0 = o.alpha_ratio * o.alpha1;
  constexpr double kTiny = 1e-12;  // keeps a face without area or edges from a zero pivot

  // The scaled form of the ALM (u = lambda / r, v = mu / r). Per interior edge:
  //   u, v    the scaled multipliers of P = DN - AW and Q = DW
  //   S, T    P + u and Q + v: all the face systems' right-hand sides need of them
  const std::vector<Vec>& N0 = geometry.normal;
  std::vector<Vec> N = N0, previous(F), rhs_n(F);
  std::vector<Mat> W(F, Mat::Zero()), rhs_w(F);
  std::vector<Vec> u(E, Vec::Zero()), S(E);
  std::vector<Mat> v(E, Mat::Zero()), T(E, Mat::Zero());
  for_each(E, [&](std::size_t e) { S[e] = N[L.faces[e][0]] - N[L.faces[e][1]]; });  // P = DN, W = 0

  // N system: (diag(a) + r D^T L D) N; Jacobi preconditioner.
  std::vector<double> n_diag_inverse(F);
  for_each(F, [&](std::size_t f) {
    double s = L.a[f] + kTiny;
    for (const Side& sd : L.side[f]) s += r * sd.l;
    n_diag_inverse[f] = 1 / s;
  });
  auto apply_n = [&](std::size_t f, const std::vector<Vec>& x) {
    Vec s = (L.a[f] + kTiny) * x[f];
    for (const Side& sd : L.side[f])
      if (sd.g != kNone) s += (r * sd.l) * (x[f] - x[sd.g]);
    return s;
  };
  auto precondition_n = [&](std::size_t f, const Vec& x) { return Vec(x * n_diag_inverse[f]); };

  // W system: (r A^T L A + r D^T L D + r diag(a) P_N) W. The last term, r a_f |W_f N_f|^2,
  // keeps W tangent to the current normals: a derivative of the normals along the normal means
  // nothing, and without the term CG crawls through that near-null space. Row block f is
  //   W_f M_f + sum_sides W_g B_fg + t_f (W_f N_f) N_f^T,
  //   M_f = sum_sides (r l/4 d d^T + r l I),  B_fg = r l/4 d d^T - r l I,  t_f = r a_f;
  // the preconditioner is block Jacobi with the input normals: W_f -> W_f (M_f + t_f N0 N0^T)^-1.
  std::vector<Mat> w_diagonal(F), w_block_inverse(F);
  auto tangent_weight = [&](std::size_t f) { return r * std::max(L.a[f], 1e-3); };
  for_each(F, [&](std::size_t f) {
    Mat m = Mat::Identity() * kTiny;
    for (const Side& sd : L.side[f])
      if (sd.g != kNone) {
        m.noalias() += (0.25 * r * sd.l) * sd.d * sd.d.transpose();
        m.diagonal().array() += r * sd.l;
      }
    w_diagonal[f] = m;
    w_block_inverse[f] = (m + tangent_weight(f) * N0[f] * N0[f].transpose()).inverse();
  });
  auto apply_w = [&](std::size_t f, const std::vector<Mat>& x) {
    Mat s = x[f] * w_diagonal[f];
    s.noalias() += (tangent_weight(f) * (x[f] * N[f])) * N[f].transpose();
    for (const Side& sd : L.side[f])
      if (sd.g != kNone) {
        const Mat& xg = x[sd.g];
        s.noalias() += ((0.25 * r * sd.l) * (xg * sd.d)) * sd.d.transpose();
        s -= (r * sd.l) * xg;
      }
    return s;
  };
  auto precondition_w = [&](std::size_t f, const Mat& x) { return Mat(x * w_block_inverse[f]); };

  Pcg<Vec> pcg_n;
  Pcg<Mat> pcg_w;
  TgvResult out;
  for (int it = 0; it < o.iterations; ++it) {
    // N: a N0 + r D^T L (P + u + AW), then normalised.
    for_each(F, [&](std::size_t f) {
      Vec s = L.a[f] * N0[f];
      for (const Side& sd : L.side[f])
        if (sd.g != kNone) s += (r * sd.l) * (sd.s * S[sd.e] + 0.5 * (W[f] + W[sd.g]) * sd.d);
      rhs_n[f] = s;
    });
    previous = N;
    out.cg_steps += pcg_n.solve(N, rhs_n, apply_n, precondition_n, o.cg_iterations, o.cg_tolerance);
    for_each(F, [&](std::size_t f) {
      const double len = N[f].norm();
      if (len > 0) N[f] /= len;
    });
    // W: r A^T L (DN - P - u) + r D^T L (Q + v).
    for_each(F, [&](std::size_t f) {
      Mat s = Mat::Zero();
      for (const Side& sd : L.side[f])
        if (sd.g != kNone) {
          s.noalias() += (0.5 * r * sd.l) * (N[f] - N[sd.g] - sd.s * S[sd.e]) * sd.d.transpose();
          s += (sd.s * r * sd.l) * T[sd.e];
        }
      rhs_w[f] = s;
    });
    out.cg_steps += pcg_w.solve(W, rhs_w, apply_w, precondition_w, o.w_cg_iterations, o.cg_tolerance);
    // W_f <- W_f (I - N_f N_f^T): exactly tangent (the penalty above only nearly). Without it a
    // W close to c I, a sphere's gradient, slips through the cube's edges at no second-order
    // cost, and the clean test cube's sides came back domed by up to 1.9 degrees (1.3 with it,
    // both run to convergence).
    for_each(F, [&](std::size_t f) { W[f] -= (W[f] * N[f]) * N[f].transpose(); });
    // P, Q by shrinkage, the multipliers, and S = P + u, T = Q + v for the next iteration.
    for_each(E, [&](std::size_t e) {
      const auto [f, g] = L.faces[e];
      const Vec x = N[f] - N[g] - 0.5 * (W[f] + W[g]) * L.d[e];
      const Vec p = shrink<Vec>(x - u[e], alpha1 / r);
      u[e] += p - x;
      S[e] = p + u[e];
      const Mat dw = W[f] - W[g];
      const Mat q = shrink<Mat>(dw - v[e], alpha0 / r);
      v[e] += q - dw;
      T[e] = q + v[e];
    });
    // How far the normals turned in this iteration: area-weighted mean and largest.
    const Vec turn = sum_each(F, [&](std::size_t f) {
      const double t = (N[f] - previous[f]).norm();
      return Vec(L.a[f] * t, L.a[f], t);
    });
    const double largest = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, F, kGrain), 0.0,
        [&](const auto& range, double m) {
          for (std::size_t f = range.begin(); f < range.end(); ++f) m = std::max(m, (N[f] - previous[f]).norm());
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
    out.iterations = it + 1;
    out.last_turn_mean_deg = chord_to_deg(turn[1] > 0 ? turn[0] / turn[1] : 0);
    out.last_turn_max_deg = chord_to_deg(largest);
    if (progress) progress(static_cast<double>(it + 1) / o.iterations);
    // (The first iteration cannot move N: P starts at DN, so the shrinkage acts from the second.)
    if (it > 0 && out.last_turn_mean_deg <= o.tolerance) break;
  }
  out.normals = std::move(N);
  return out;
}

}  // namespace scallop
