// Denoising a point cloud by moving-least-squares (MLS) projection onto local quadrics.
//
// Every point q is projected onto a smooth surface fitted to its neighbourhood (Levin, "Mesh-
// independent surface interpolation", 2003; Alexa, Behr, Cohen-Or, Fleishman, Levin, Silva,
// "Computing and rendering point set surfaces", IEEE TVCG 2003, section 3):
//   1. a reference plane H through the Gaussian-weighted centroid of the neighbours, with the
//      normal n of the smallest eigenvalue of their weighted covariance (weights centred at q);
//   2. a local frame (t1, t2, n) with its origin at q, and the weighted least-squares quadric
//      w = a + b u + c v + d u^2 + e u v + f v^2 over the neighbours' frame coordinates (u, v, w);
//   3. q moves to the quadric point above (u, v) = (0, 0): q' = q + a n, the normal of the
//      quadric there being proportional to n - b t1 - c t2.
// Here the plane is taken in one step (the weighted PCA plane) rather than by Levin's non-linear
// minimisation; the quadric absorbs the offset between q and the plane. A point therefore only
// ever moves along its local normal: one-sided neighbourhoods at the boundary of the cloud cannot
// pull it inwards, and the sampling in the tangent plane is kept.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

#include "nodes/types/cloud.h"

namespace scallop {

struct DenoiseOptions {
  int k = 0;               // neighbours in each fit (the point itself excluded), >= 5; or 0:
                           // automatic, from the estimated noise and `tolerance` (see
                           // choose_denoise_k; with scales > 1 the widest fit takes `widen`
                           // times that); the cloud is returned unchanged when the noise is
                           // already below `tolerance`
  int widen = 4;           // automatic k with scales > 1: the widest fit's neighbours, times the
                           // one-scale k. The lack-of-fit test and the agreement with the
                           // narrower fits keep a wide fit only where the surface is smooth
                           // enough for it, and there 4 halves the standard error (median
                           // uncertainty of the catalog's noisy clouds, sigma 0.02 mm: 0.019-0.021
                           // -> 0.010-0.016 mm, and their plane, dome, bowl and saddle are planned
                           // at h = 0.05 where 1 refused them; denoising takes about 4 times
                           // longer: 1.25 -> 4.97 s on the noisy plane's 50 000 points). The
                           // default since cloud.denoise v8: 1 had been, because 4 took the
                           // bundled example's certificate to a gouge bound of 0.0106 at its rim
                           // (stop 33); with the rim passes and the guard since, it passes
                           // (0.0079 zig-zag, 0.0078 contour).
  int degree = 3;          // the local polynomial: 2, a quadric; 3, a cubic (10 terms). Inside the
                           // cloud, where a neighbourhood is about symmetric, the cubic terms are
                           // nearly orthogonal to the offset, so its noise is the quadric's
                           // (local polynomials of degree p and p + 1 estimate a value with the
                           // same variance for even p: Fan and Gijbels, "Local polynomial
                           // modelling and its applications", 1996, section 3.3), while the
                           // residuals no longer hold the surface's third derivative: on the
                           // waves the lack-of-fit test narrowed 77 % of the quadric fits at
                           // k = 1200 for it, a misfit that does not move the fitted offset.
                           // Per point: the cubic where its widest fit's standard error is within
                           // 1.1 times the quadric's (inside), the quadric elsewhere (a one-sided
                           // neighbourhood at the rim couples the cubic terms with the offset),
                           // the same degree at every scale of the point. Below k = 64 the
                           // quadric whatever this says.
  double tolerance = 0.002;  // mm; automatic mode only: the normal error (RMS) aimed at
  double radius = 0;       // mm; R, the neighbourhood radius: of the k nearest neighbours only
                           // those within R are used, with Gaussian weights exp(-2 d^2 / R^2).
                           // 0: automatic, per point: the smallest distance to the k-th
                           // neighbour over the point and its k neighbours (so that a point on
                           // the cloud's boundary keeps the interior's radius)
  int iterations = 1;      // projections in sequence, each on the result of the previous one
  bool set_normals = true; // output normals from the quadric's gradient
  bool equalize_rim = true; // refit points whose standard error is above 1.15 times the median
                            // (one-sided neighbourhoods near the rim) from 2 k neighbours
  int scales = 7;           // fits from k / 2^(scales-1) (at least 16) to k neighbours; each
                            // point keeps the widest one that agrees with the narrower ones and
                            // follows the surface (a Lepski-type rule, see mls_denoise) and its
                            // uncertainty counts the bias left; 1: k only, the uncertainty counts
                            // noise only (not honest where the shape is sharp for the
                            // neighbourhood: a crest)
  double ici_gamma = 4.0;   // how many noise spreads two nested fits may differ by and agree
                            // (on a noisy plane, k = 1200: 3 narrowed 1 % of the points by
                            // chance, each then 2-8 times less certain and 0.045 mm off at
                            // worst; 4 narrowed 0.04 %, worst error 0.016; a crest's bias
                            // the scales cannot see is left to the lack-of-fit test)
  double bias_growth = 1.5; // a fit's bias grows at least by 2^bias_growth per doubling of k
                            // (as the cube of its radius)
  double misfit_z = 5.0;    // a wider fit is kept only while its residual variance is within
                            // misfit_z of its own spread of sigma^2 (a lack-of-fit test; 0: none).
                            // 5, not 4: some 300 000 such tests a 50 000-point cloud, and at 4 the
                            // noisy saddle (an exact quadric) had a cluster of 24 points narrowed
                            // by chance, up to 0.083 mm uncertain where they were 0.011 off, and a
                            // program that verify.py measured 0.0536 there; at 5 none, and the
                            // largest |error| / uncertainty is 0.80-0.89 on six crests of radius
                            // 1, 3 and 10 mm, at most 0.92 (freeform) on the catalog's noisy
                            // clouds (bench/extra_surfaces.py error, cubic fits inside)
  int bias_scales = 2;      // how many narrower scales next to the kept one bound its bias
                            // (0: all of them). 2, not 3: on a smooth surface the bound is the
                            // narrower fits' noise (each scale down doubles its variance), and
                            // its upper tail, not its median, sets a strip's margins: on the noisy
                            // plane (k = 1192) the 99th percentile of the uncertainty 0.0179 ->
                            // 0.0153 mm, the zig-zag program's efficiency 0.431 -> 0.469. The
                            // crests' bias shows at the nearest narrower scale and in the
                            // lack-of-fit test: the largest |error| / uncertainty over the 12
                            // noisy clouds of bench/extra_surfaces.py (the catalog and 5 crests)
                            // at most 0.929, at 1 0.954; but at 1 the model between the points of
                            // the 1 mm crest came to 1.014 (0.898 at 2 and 3).
  double share = 0.1;        // the three widest scales (k, k/2, k/4) are fitted once at centres
                            // this times the neighbourhood's radius R apart (each point within
                            // that of one), and each point evaluates its nearest centre's fits
                            // at itself, with the standard error there; the narrower scales,
                            // which a crest or a rim changes within a spacing, stay its own. On the
                            // catalog's noisy clouds (50 000 points, sigma 0.02, k ~ 1 200) a
                            // centre per 6.5 points, denoising 1.9 times faster, the median
                            // uncertainty 1 % higher, the largest |error| / uncertainty over 15
                            // clouds 0.960 as with every point's own fits. 0: every point its own
                            // fits at every scale (so too with a fixed `radius`, given
                            // neighbourhoods, or fewer than 4 scales)
};

struct DenoiseResult {
  std::vector<Eigen::Vector3d> points;   // #P moved positions (mm)
  std::vector<Eigen::Vector3d> normals;  // #P unit normals, or empty when !set_normals
  std::size_t kept = 0;  // points left in place in the last iteration (degenerate neighbourhood)
  std::size_t refitted = 0;  // rim points refitted from a wider neighbourhood (all iterations)
  std::size_t refits_biased = 0;  // of those, kept with the narrower fit: the wider one moved
                                  // the point further than noise can (a curved rim)
  int k = 0;               // neighbours per fit actually used (0 when skipped)
  double noise_sigma = -1; // mm; estimated noise (estimate_noise_sigma)
  bool skipped = false;    // automatic mode found noise_sigma < tolerance: points left as they are
  double moved_rms = 0;    // mm; RMS distance between the input and the output points
  // mm, #P (empty when skipped): the standard error of each output point along its normal,
  // noise_sigma * sqrt(e0^T A^-1 B A^-1 e0) of its (last) fit; noise_sigma itself for a point
  // left in place
  std::vector<double> standard_error;
  std::vector<double> bias;  // mm, #P (empty when skipped): bound on the kept fit's shape bias
  // mm, #P: how far each point may be off the real surface, the model the certificate rests on:
  // uncertainty_factor(scales) * standard_error + bias; when skipped, the points being the input
  // ones, uncertainty_factor(scales) * noise_sigma for every point; at least kUncertaintyFloor
  std::vector<double> uncertainty;
  std::size_t shared_centres = 0;  // centres of the shared wide fits (0: not shared)
  std::size_t narrowed = 0;  // points kept with a narrower fit than k (sharp shape)
  std::size_t unnarrowed = 0;  // points narrowed alone (by chance) given the widest fit back
  // The uncertainty in brief, for reports (mm): its median (the upper one of an even count),
  // its largest value and the output point that has it (the first such), the number of standard
  // errors it counts (uncertainty_factor(scales)), and the largest bias bound (0 when skipped).
  double uncertainty_median = 0;
  double uncertainty_max = 0;
  Eigen::Vector3d uncertainty_max_at = Eigen::Vector3d::Zero();
  double uncertainty_factor = 0;
  double bias_max = 0;
};

// How many standard errors a denoised point may lie off the real surface: the bound stored as
// the cloud's per-point uncertainty, uncertainty = factor * standard_error + bias.
// One scale (bias not counted): 4. Measured on 50k-point clouds of the plane, waves, dome,
// saddle and canopy surfaces with sigma = 0.02 mm (k = 301): the largest |error| / standard error
// was 3.8 to 4.1 inside, up to 4.4 near the canopy's steep rim; but on a rounded crest (radius
// 3 mm, flanks of slope 0.7) the wide fit's shape bias reached 2.9 times that bound.
// Several scales (bias bound added): 6. Noise shared by the nested fits of one point (a cluster
// of noisy samples) can hide part of a bias, and a point's error is its fit's noise and bias at
// once, so the factor is above the ~4 noise alone needs. Measured largest |error| / uncertainty
// (bench/extra_surfaces.py error, 50k points, sigma = 0.02, k ~ 300, 5 scales): plane 0.59,
// waves 0.52, canopy 0.66, crests of radius 1 and 3 mm with flanks of slope 0.7: 0.93 and 0.93
// (with 5.5: 1.00 on both crests; with 4: 1.31, 1.32). The median uncertainty is then 0.024 mm
// against 0.0106 with one scale. Since 7 scales up to 4 times k, the lack-of-fit test and the
// bias from the 3 nearest narrower scales (k ~ 1200): median 0.0103-0.0156 mm, largest |error| /
// uncertainty 0.49 (plane) to 0.91 (freeform) over the catalog's noisy clouds, 0.68-0.90 on
// crests of radius 1, 3 and 10 mm (bench/extra_surfaces.py error).
inline constexpr double kUncertaintyFactor = 4.0;
// No cloud is known better than this (mm): below it, float storage (a float32 coordinate of
// 100 mm is rounded to 4e-6 mm) and any scanner's resolution. Without it an exact clean cloud's
// uncertainty, 4 times a noise estimate of rounding errors, was exceeded by its rounding errors
// (largest |error| / uncertainty 1.01 on the catalog's clean plane).
inline constexpr double kUncertaintyFloor = 1e-4;
inline constexpr double kUncertaintyFactorMultiScale = 6.0;
inline double uncertainty_factor(int scales) {
  return scales > 1 ? kUncertaintyFactorMultiScale : kUncertaintyFactor;
}

// Noise level of a sampled surface: for up to `samples` points (evenly spaced in index order; all
// when #P <= samples), a Gaussian-weighted quadric is fitted to the point and its `k` nearest
// neighbours exactly as in the projection below (PCA frame, weight exp(-2 d^2 / R^2), R the
// distance to the k-th neighbour), and its residual variance in the normal direction is
//   s_i^2 = sum_j w_j r_j^2 / (sum_j w_j - tr(A^-1 B)),   A = Phi^T W Phi, B = Phi^T W^2 Phi,
// the denominator being E[sum w r^2] / sigma^2 for a weighted least-squares fit with 6
// coefficients (it replaces the usual m - 6). The result is the median of the s_i, divided by the
// median of a chi distribution with the fits' effective degrees of freedom
// nu = (sum w)^2 / sum w^2 - 6 (Wilson-Hilferty: median(chi^2_nu / nu) ~ (1 - 2 / (9 nu))^3),
// so that it estimates sigma, the standard deviation of independent noise along the normal
// (for isotropic noise of sigma per axis, that sigma). The median ignores the few fits spoiled by
// creases or outliers; on a smooth clean surface the result is the quadric's fitting error (tiny
// when the sampling is fine against the curvature).
// P  #P by 3 positions (mm), finite. Returns 0 when no neighbourhood could be fitted (fewer than
// 10 points, all collinear...).
// Throws std::invalid_argument for an empty cloud, a non-finite coordinate, k < 10, samples < 1.
double estimate_noise_sigma(const std::vector<Eigen::Vector3d>& P, int k = 32, int samples = 2000);

// The automatic k for noise sigma and a wanted normal error `tolerance` (both mm, tolerance > 0):
//   k = clamp(round(c (sigma / tolerance)^2), 32, 512),  c = 3.
// The projection's noise falls as sigma * sqrt(c0 / k) with c0 ~ 5.5 (measured on 50k-point
// clouds, sigma = 0.02 mm: RMS 0.0060 at k = 64, 0.0029 at 256, 0.0021 at 512), so RMS = tolerance
// would need c = c0; but the shape bias of a wide fit grows with k (on clean clouds: +0.0018 mm
// max at k = 256, +0.0074 at 384 on a curved canopy) while the noise gains little past k ~ 300,
// hence c = 3 (sigma = 0.02, tolerance = 0.002 -> k = 300, RMS ~ 1.35 tolerance).
int choose_denoise_k(double sigma, double tolerance);

// P      #P by 3 positions (mm), all finite
// N      #P by 3 unit normals, or empty: only used to orient the output normals (the fitted
//        normal is flipped to agree with N_i, or with +Z when N is empty)
// nbrs   optional neighbourhoods of P (e.g. compute_knn(P, k)); when given, the first
//        min(k, nbrs.k) neighbours of each point are used in every iteration, with distances
//        recomputed from the moved positions. When null, a k-d tree is built over the current
//        positions in each iteration (k is clamped to #P - 1).
// progress  optional, called with the fraction done in [0, 1].
// A point whose neighbourhood is degenerate (fewer than 6 points with weight, all collinear, or a
// singular quadric fit) is kept as it is (and its normal taken from N, or +Z when N is empty).
// With k = 0 (automatic): sigma = estimate_noise_sigma(P); if sigma < tolerance, points = P and
// normals = N (as given, possibly empty) come back with skipped = true; otherwise k = choose_denoise_k(sigma, tolerance) (at most nbrs->k when nbrs is given).
// Throws std::invalid_argument for an empty cloud ("the cloud is empty"), a non-finite
// coordinate, N or nbrs not matching P, 0 < k < 5 or k < 0, radius < 0 or non-finite,
// iterations < 0, tolerance <= 0 or non-finite (automatic mode).
DenoiseResult mls_denoise(const std::vector<Eigen::Vector3d>& P,
                          const std::vector<Eigen::Vector3d>& N, const DenoiseOptions& options,
                          const Neighborhoods* nbrs = nullptr,
                          const std::function<void(double)>& progress = {});

}  // namespace scallop
