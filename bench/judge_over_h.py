#!/usr/bin/python3
"""Where and why the judge finds a whole part's scallop over h (issue 14): runs
../shared/tools/verify_part.py's measurement on a run's programs, keeps its samples, and splits
those left over 1.01 h by cause:

- the envelope: how deep the true part lies inside the mesh the balls were kept off
  (mesh.cloud_envelope's outer mesh); where that is more than the sample's excess over h, a ball
  that touched the outer mesh could not have cut the excess; and, wider, how far the ball tangent
  to the true part at the sample reaches into the outer mesh (anywhere within its radius): where
  that is more than the excess, no ball kept off the outer mesh could have cut it, and how far the
  outer mesh stands outside the true part where that ball meets it;
- the patch surfaces: their distance from the sample (surfaces.ply, its face label the patch);
- the true part's sharp edges: how near the sample is to one.

  bench/judge_over_h.py graph GRAPH.json OUT_GRAPH.json    # the graph, writing outer.ply too
  bench/judge_over_h.py measure OUT TRUE_MESH --scale S --tool-radius R --scallop H --chord E

OUT is the run's output folder: setups.json, base_report.json, surfaces.ply and, for the envelope
figures, outer.ply (run the graph made by the first form). Prints the over-h fraction the judge
reports, then the figures above for the over-h samples beside the same for 100 000 samples the
programs cut, and the patches with the most samples over h.
"""
import argparse, json, os, struct, sys

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
sys.path.insert(0, TOOLS)
import mesh3d  # noqa: E402
import verify_part  # noqa: E402


def graph_with_outer(src, dst):
    g = json.load(open(src))
    ids = {n["id"] for n in g["nodes"]}
    if "envelope" not in ids:
        sys.exit("%s has no node 'envelope' (mesh.cloud_envelope)" % src)
    g["nodes"].append({"id": "write_outer", "type": "io.write_mesh", "inputs": {"mesh": "envelope.outer"},
                       "params": {"path": "outer.ply"}})
    json.dump(g, open(dst, "w"), indent=1)


def judge_samples(out, true_mesh, a):
    """verify_part.py's samples: positions, normals, status (0 cut, 1 uncut, 2 base, 3 out of
    reach, 4 gouged) and scallop, with its report."""
    base = json.load(open(os.path.join(out, "base_report.json")))["base_direction"]
    argv = ["--mesh", true_mesh, "--scale", str(a.scale), "--setups", os.path.join(out, "setups.json"),
            "--base-normal=" + ",".join(str(x) for x in base), "--tool-radius", str(a.tool_radius),
            "--scallop", str(a.scallop), "--chord", str(a.chord), "--plot", os.devnull]
    kept = {}

    def keep(fname, mesh, P, N, status, scallop, H, tol, spacing, report):
        kept.update(P=P, N=N, status=status, scallop=np.nan_to_num(scallop))
    verify_part.plot = keep  # its plot is handed every sample; nothing is drawn
    report, _ = verify_part.measure(verify_part.parse_args(argv))
    return kept["P"], kept["N"], kept["status"], kept["scallop"], report


def patch_faces(path):
    """surfaces.ply's triangles (fans of its quads) and each one's patch label."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + 11
    header = data[:end].decode().split("\n")
    count = lambda what: int(next(l for l in header if l.startswith("element " + what)).split()[2])
    nv, nf = count("vertex"), count("face")
    V = np.frombuffer(data[end:end + 24 * nv], "<f8").reshape(-1, 3)
    at, T, label = end + 24 * nv, [], []
    for _ in range(nf):
        k = data[at]
        idx = np.frombuffer(data[at + 1:at + 1 + 4 * k], "<u4")
        (lab,) = struct.unpack("<i", data[at + 1 + 4 * k:at + 5 + 4 * k])
        at += 5 + 4 * k
        for j in range(1, k - 1):
            T.append((idx[0], idx[j], idx[j + 1]))
            label.append(lab)
    return V, np.array(T), np.array(label)


def quantiles(x):
    return " ".join("%.4f" % q for q in np.quantile(x, [0.5, 0.9, 0.99])) if len(x) else "-"


def measure(a):
    P, N, status, scallop, report = judge_samples(a.out, a.true_mesh, a)
    H = a.scallop
    cut = status == 0
    over = cut & (scallop > 1.01 * H)
    rng = np.random.default_rng(0)
    some = rng.choice(np.flatnonzero(cut), min(100000, int(cut.sum())), replace=False)
    print("judge: %s, %.3f %% of the measured area over 1.01 h (interior %.3f %%, p99 %.5f mm), gouge %.5f mm, "
          "uncut %.3g, %d samples over, %d cut" % ("pass" if report["pass"] else "fail", 100 * report["frac_over_limit"],
                                                  100 * report["frac_over_limit_interior"], report["scallop_p99_interior"],
                                                  report["gouge_max"], report["uncut_fraction"], over.sum(), cut.sum()))
    print("judge: cut %.1f m, rapids %.1f m (least clearance %.4f mm, %d through the part)%s" % (
        report["cut_length"] / 1000, report["rapid_length"] / 1000, report["rapid_min_clearance"],
        report["rapids_through_part"], "; " + "; ".join(report["fail_reasons"]) if report["fail_reasons"] else ""))
    if not over.any():
        return
    print("%-44s %-26s %-26s" % ("median p90 p99 (mm)", "over 1.01 h", "cut samples"))
    truth = mesh3d.Mesh(*mesh3d.load_mesh(a.true_mesh, a.scale)[:2])
    edges = truth.feature_edges(a.angle)[0]
    pieces = [e[0] + (e[1] - e[0]) * t[:, None] for e in edges
              for t in [np.linspace(0, 1, max(2, int(np.linalg.norm(e[1] - e[0]) / 0.05)))]]
    edge_tree = cKDTree(np.vstack(pieces)) if pieces else None
    if edge_tree is not None:
        d_over, d_some = edge_tree.query(P[over])[0], edge_tree.query(P[some])[0]
        print("%-44s %-26s %-26s" % ("distance to a true edge over %g deg" % a.angle, quantiles(d_over), quantiles(d_some)))
        print("%-44s %-26.3f %-26.3f" % ("  share within 0.5 mm of one", np.mean(d_over < 0.5), np.mean(d_some < 0.5)))
    V, T, label = patch_faces(os.path.join(a.out, "surfaces.ply"))
    surfaces = mesh3d.MeshIndex(mesh3d.Mesh(V, T), 0.5)
    s_over, piece = surfaces.distance(P[over], cap=1.0, piece=True)
    print("%-44s %-26s %-26s" % ("distance to the patch surfaces", quantiles(s_over), quantiles(surfaces.distance(P[some], cap=1.0))))
    outer_path = os.path.join(a.out, "outer.ply")
    if os.path.exists(outer_path):
        outer = mesh3d.MeshIndex(mesh3d.Mesh(*mesh3d.load_mesh(outer_path)[:2]), 0.5)
        deep_over, deep_some = -outer.signed(P[over], cap=1.0), -outer.signed(P[some], cap=1.0)
        print("%-44s %-26s %-26s" % ("depth of the truth inside the outer mesh", quantiles(deep_over), quantiles(deep_some)))
        print("over-h samples deeper inside the outer mesh than their excess: %.1f %%"
              % (100 * np.mean(deep_over >= scallop[over] - H)))
        # The ball tangent to the true part at each over-h sample: how far it reaches into the outer
        # mesh, and where it meets it, how far the outer mesh stands outside the true part.
        centre = P[over] + a.tool_radius * N[over]
        dist, touched = outer.distance(centre, cap=2 * a.tool_radius, piece=True)
        reach = a.tool_radius - dist
        blocked = reach > scallop[over] - H
        print("%-44s %-26s" % ("reach of the tangent ball into the outer mesh", quantiles(reach)))
        print("over-h samples whose tangent ball reaches into the outer mesh by more than their excess: %.1f %%"
              % (100 * np.mean(blocked)))
        if blocked.any():
            T = outer.mesh.V[outer.mesh.F[outer.owner[touched[blocked]]]]
            where, _ = mesh3d.closest_on_triangle(centre[blocked], T[:, 0], T[:, 1], T[:, 2])
            true_index = mesh3d.MeshIndex(truth, 0.5)
            print("%-44s %-26s" % ("  where it meets it: outer over the true part", quantiles(true_index.signed(where, cap=2.0))))
            if edge_tree is not None:
                print("%-44s %-26s" % ("  where it meets it: distance to a true edge", quantiles(edge_tree.query(where)[0])))
    else:
        print("(no outer.ply in %s: run the graph made by the 'graph' form for the envelope's figures)" % a.out)
    patch = label[surfaces.owner[piece]]
    _, every = surfaces.distance(P[cut], cap=1.0, piece=True)
    per_cut = np.bincount(label[surfaces.owner[every]], minlength=label.max() + 1)
    per_over = np.bincount(patch, minlength=label.max() + 1)
    print("patches with the most samples over 1.01 h (nearest surface):")
    for p in np.argsort(-per_over)[:a.patches]:
        if per_over[p]:
            print("  patch %3d: %6d of %7d (%.1f %%)" % (p, per_over[p], per_cut[p], 100 * per_over[p] / max(1, per_cut[p])))


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "graph":
        return graph_with_outer(sys.argv[2], sys.argv[3])
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["measure"])
    ap.add_argument("out")
    ap.add_argument("true_mesh")
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--tool-radius", type=float, required=True)
    ap.add_argument("--scallop", type=float, required=True)
    ap.add_argument("--chord", type=float, required=True)
    ap.add_argument("--angle", type=float, default=20.0, help="degrees: sharper true edges count")
    ap.add_argument("--patches", type=int, default=8, help="patches listed")
    measure(ap.parse_args())


if __name__ == "__main__":
    main()
