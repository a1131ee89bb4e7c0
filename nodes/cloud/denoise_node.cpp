#include <cstdio>
#include <stdexcept>

#include "engine/node.h"
#include "nodes/cloud/denoise.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"

namespace scallop::cloud_nodes {

NodeDecl make_denoise_node() {
  NodeDecl d;
  d.type = "cloud.denoise";
  d.version = 13;  // 2: automatic k, tolerance, report; 3: rim refits, per-point uncertainty; 4: biased rim refits refused; 5: multi-scale fits, bias in the uncertainty, a 0.1 um floor; 6: 5 scales by default; 7: 7 scales, `widen`, a lack-of-fit test, the bias from the 3 nearest narrower scales, lone narrowings undone; 8: `widen` 4 by default; 9: a cubic fit inside (`degree` 3), `misfit_z` 5; 10: `bias_scales` 2; 11: neighbours summed in the search's order, residuals from the normal equations (the same points to 1e-12 mm; the noisy plane's denoising graph 7.81 -> 4.22 s); 12: the three widest scales shared between nearby points (`share` 0.1; the noisy plane's denoising 3.55 -> 1.83 s); 13: the fits sum moments of monomials, not every entry of their normal matrices (the same points to 1e-14 mm; CPU 0.83 times)
  d.description =
      "moving-least-squares denoising: each point projected along its local normal onto a "
      "weighted cubic (inside) or quadric (at the rim) fitted to its neighbours, at the widest of several scales (k, k/2, ... "
      "k/64) that agrees with the narrower ones and whose residuals are noise, so crests and "
      "creases are not flattened (parallel)";
  d.input("cloud", "Cloud", "the noisy points; their normals, if any, only orient the new ones")
      .input("neighbors", "Neighbors",
             "neighbours of each point (its first k are used); computed here when absent", false)
      .output("cloud", "Cloud",
              "the projected points (the input points when automatic mode finds them smooth "
              "enough), with normals from the fitted quadrics and a per-point uncertainty: "
              "4 standard errors of the fit (or of the estimated noise), at least 0.1 um; with scales > 1, 6 "
              "standard errors of the kept fit plus a bound on its shape bias; path planners "
              "keep it as a margin")
      .output("report", "Report",
              "{noise_sigma (mm, estimated), k (used; 0 when skipped), moved_rms (mm), skipped, "
              "rim_refitted (points refitted from a wider neighbourhood), rim_refits_biased (of those, kept with the narrower fit because the wider one was biased), narrowed (points kept with a narrower fit than k: sharp shape), unnarrowed (points narrowed alone, by chance, given the widest fit back), bias_max (mm), shared_centres (centres of the shared wide fits), uncertainty {median, "
              "max, max_at, factor}: how far the points may still be off the real surface}");
  d.options<DenoiseOptions>()
      .integer("k", &DenoiseOptions::k, 0, 4096, "",
               "neighbours in the widest fit; more averages more noise away (noise in the normal "
               "direction falls roughly as 1/sqrt(k)) but smooths more of the shape. 0: "
               "automatic: the noise sigma is estimated from local quadric fits; below "
               "`tolerance` the cloud passes unchanged, otherwise k = clamp(3 (sigma / "
               "tolerance)^2, 32, 512), times `widen` with scales > 1")
      .integer("widen", &DenoiseOptions::widen, 1, 8, "",
               "automatic k with scales > 1: the widest fit takes this many times the one-scale "
               "k. 4 (the default) halves the uncertainty of smooth noisy clouds against 1 (sigma "
               "0.02 mm: median 0.010 mm, and h = 0.05 becomes plannable) and takes about 4 times "
               "as long")
      .integer("degree", &DenoiseOptions::degree, 2, 3, "",
               "the local polynomial fitted: 2 a quadric, 3 a cubic where it is as certain as the "
               "quadric (inside the cloud; the quadric at the rim and below k = 64): its residuals "
               "no longer hold the surface's third derivative, so wide fits are kept on smooth "
               "curved surfaces")
      .number("tolerance", &DenoiseOptions::tolerance, 1e-6, 1e3, "mm",
              "automatic mode (k = 0): the normal error the denoised cloud should reach; "
              "clouds with less estimated noise are left as they are")
      .number("radius", &DenoiseOptions::radius, 0.0, 1e6, "mm",
              "neighbourhood radius R (of the k nearest, those within R count, Gaussian "
              "weights exp(-2 d^2/R^2)); 0: automatic, the smallest k-th neighbour distance "
              "around each point")
      .integer("iterations", &DenoiseOptions::iterations, 0, 20, "", "projections in sequence")
      .integer("scales", &DenoiseOptions::scales, 1, 8, "",
               "fits at k, k/2, ... (down to 16 neighbours); each point keeps the widest that "
               "agrees with the narrower ones and passes the lack-of-fit test, so a crest or "
               "crease is not flattened, and its uncertainty is 6 standard errors plus the bias "
               "bound from the other scales (honest on crests; the default). 1: one fit of k; "
               "uncertainty 4 standard errors, noise only, which a crest or crease sharp for the "
               "neighbourhood exceeds")
      .integer("bias_scales", &DenoiseOptions::bias_scales, 0, 8, "",
               "how many narrower scales next to the kept one bound its bias (0: all; each "
               "narrower one is noisier, and on a smooth surface its noise, not a bias, sets the "
               "bound)")
      .number("misfit_z", &DenoiseOptions::misfit_z, 0.0, 10.0, "",
              "lack-of-fit test: a wider fit is kept only while its residual variance is within "
              "this many of its own spreads of the noise's (0: no test)")
      .number("ici_gamma", &DenoiseOptions::ici_gamma, 0.5, 10.0, "",
              "how many noise spreads two nested fits may differ by and still agree")
      .number("bias_growth", &DenoiseOptions::bias_growth, 0.25, 3.0, "",
              "a fit's bias is taken to grow at least by 2^bias_growth per doubling of k")
      .number("share", &DenoiseOptions::share, 0.0, 0.5, "",
              "the three widest scales are fitted once at centres this many neighbourhood radii "
              "apart, and each point evaluates its nearest centre's fits at itself (its "
              "standard error there counts the distance); its narrower fits stay its own. 0: "
              "every point its own fits (about 1.9 times longer)")
      .flag("normals", &DenoiseOptions::set_normals,
            "set normals from the fitted quadrics (oriented like the input normals, or "
            "+Z); otherwise the input normals are kept");
  d.run = [](NodeContext& ctx) {
    auto cloud = ctx.input<PointCloud>("cloud");
    if (cloud->size() == 0) throw NodeError("the cloud is empty");
    std::shared_ptr<const Neighborhoods> nbrs;
    if (ctx.has_input("neighbors")) nbrs = ctx.input<Neighborhoods>("neighbors");
    const DenoiseOptions o = ctx.options<DenoiseOptions>();
    static const std::vector<Eigen::Vector3d> none;
    const auto& N = cloud->has_normals() ? cloud->normals : none;
    DenoiseResult r;
    try {
      r = mls_denoise(cloud->points, N, o, nbrs.get(),
                      [&](double f) { ctx.progress(f, "denoising"); });
    } catch (const std::invalid_argument& e) {
      throw NodeError(e.what());
    }
    const Eigen::Vector3d& at = r.uncertainty_max_at;
    Report report;
    report.data = {{"noise_sigma", r.noise_sigma},
                   {"k", r.k},
                   {"moved_rms", r.moved_rms},
                   {"skipped", r.skipped},
                   {"rim_refitted", r.refitted},
                   {"rim_refits_biased", r.refits_biased},
                   {"narrowed", r.narrowed},
                   {"unnarrowed", r.unnarrowed},
                   {"shared_centres", r.shared_centres},
                   {"bias_max", r.bias_max},
                   {"uncertainty", {{"median", r.uncertainty_median},
                                    {"max", r.uncertainty_max},
                                    {"max_at", {at.x(), at.y(), at.z()}},
                                    {"factor", r.uncertainty_factor}}}};
    ctx.set("report", std::move(report));
    if (r.skipped) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "estimated noise %.2g mm is below the tolerance %.2g mm: cloud unchanged",
                    r.noise_sigma, o.tolerance);
      ctx.progress(1.0, msg);
      PointCloud out = *cloud;
      out.uncertainty = std::move(r.uncertainty);
      ctx.set("cloud", std::move(out));
      return;
    }
    PointCloud out;
    out.points = std::move(r.points);
    out.normals = o.set_normals ? std::move(r.normals) : cloud->normals;
    out.uncertainty = std::move(r.uncertainty);
    ctx.set("cloud", std::move(out));
  };
  return d;
}

}  // namespace scallop::cloud_nodes
