#!/usr/bin/python3
"""The surfaces table (issue 13): the CAD meshes of ../shared/data through
graphs/mesh-to-surfaces.json, and 200 000-point clouds sampled from them (sigma 0.02 mm) through
graphs/cloud-to-surfaces.json; the fitted surfaces measured against the true mesh by the
independent ../shared/tools/compare_mesh.py.

  bench/surfaces_table.py [--parts fandisk,block,abc] [--sources mesh,cloud] [--n 200000]
                          [--noise 0.02] [--work /tmp/scallop-surfaces-table] [--docs docs/surfaces]

Prints a Markdown table and writes it (with every report) under --work; with --docs also
docs/surfaces.md and the fandisk's pictures. Columns: quads (QuadriFlow) and their extraordinary
points, the share of the feature curves on quad edges; the base found; patches (SHFs) and the
smallest n.d over all of them; B-spline poles in all; the largest distance from a quad vertex to
its surface (fit_max_error) and from a surface to its quads (facet sag and bulges); how far the
surfaces lie from the true mesh (compare_mesh.py, surfaces sampled; mean, p99, max); wall time,
the slowest nodes and the memory peak.
"""
import argparse, json, os, shutil, sys, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mesh_table import PARTS, PY, ROOT, SHARED, TOOLS, node_times, run  # noqa: E402

def hand_made_fandisk_eps():
    """Extraordinary points (interior vertices of valence != 4) of the hand-made fandisk quads."""
    words = open(os.path.join(SHARED, "data/fandisk/fandisk_quads.off")).read().split()
    nv, nf = int(words[1]), int(words[2])
    at = 4 + 3 * nv
    valence = {}
    edges = set()
    for _ in range(nf):
        k = int(words[at])
        f = [int(w) for w in words[at + 1:at + 1 + k]]
        at += 1 + k
        for a, b in zip(f, f[1:] + f[:1]):
            edges.add((min(a, b), max(a, b)))
    for a, b in edges:
        valence[a] = valence.get(a, 0) + 1
        valence[b] = valence.get(b, 0) + 1
    return sum(1 for v in valence.values() if v != 4), nf

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default="fandisk,block,abc")
    ap.add_argument("--sources", default="mesh,cloud")
    ap.add_argument("--n", type=int, default=200000)
    ap.add_argument("--noise", default="0.02")
    ap.add_argument("--work", default="/tmp/scallop-surfaces-table")
    ap.add_argument("--docs", default="")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    scallop = os.path.join(ROOT, "build", "scallop")
    rows = []
    for part in a.parts.split(","):
        mesh_rel, scale = PARTS[part]
        truth = os.path.join(SHARED, mesh_rel)
        for source in a.sources.split(","):
            out = os.path.join(a.work, f"{part}_{source}")
            shutil.rmtree(out, ignore_errors=True)
            events = out + ".events.jsonl"
            if source == "mesh":
                cmd = [scallop, "run", os.path.join(ROOT, "graphs", "mesh-to-surfaces.json"), "--input", f"mesh={truth}",
                       "--set", f"read.scale={scale}"]
            else:
                cloud = os.path.join(a.work, f"{part}_n{a.noise}.ply")
                if not os.path.exists(cloud):
                    run([PY, os.path.join(TOOLS, "sample_mesh.py"), "--mesh", truth, "--n", str(a.n), "--seed", "1",
                         "--scale", str(scale), "--noise", a.noise, "-o", cloud])
                cmd = [scallop, "run", os.path.join(ROOT, "graphs", "cloud-to-surfaces.json"), "--input", f"cloud={cloud}"]
            t0 = time.time()
            r = run(["/usr/bin/time", "-f", "peak_kib %M"] + cmd + ["-o", out, "--no-cache", "-q", "--events", events])
            row = {"part": part, "source": source if source == "mesh" else f"cloud {a.n} sigma {a.noise}",
                   "wall_s": round(time.time() - t0, 1), "ok": r.returncode == 0}
            peak = [l for l in r.stderr.splitlines() if l.startswith("peak_kib")]
            row["peak_mib"] = round(int(peak[-1].split()[1]) / 1024) if peak else 0
            if not row["ok"]:
                row["error"] = [l for l in r.stderr.splitlines() if "error" in l][-1:] or r.stderr[-300:]
            else:
                rep = json.load(open(os.path.join(out, "segments_report.json")))
                q = rep["quad_mesh"]
                cmp_json = os.path.join(out, "compare.json")
                run([PY, os.path.join(TOOLS, "compare_mesh.py"), "--result", os.path.join(out, "surfaces.ply"),
                     "--truth", truth, "--scale-truth", str(scale), "--json", cmp_json])
                d = json.load(open(cmp_json))["distance"]["result_to_truth"]
                p = rep["patches"]
                row.update({
                    "quads": q["quads"], "quad_fraction": q["quad_fraction"], "eps": q["extraordinary_points"],
                    "feature_share": q["feature_share"], "base": rep["base_direction"], "patches": len(p),
                    "min_normal_dot": min(x["min_normal_dot"] for x in p),
                    "poles": sum(x["poles"][0] * x["poles"][1] for x in p),
                    "fit_max": rep["fit_max_error"], "fit_mean": sum(x["fit_mean_error"] for x in p) / len(p),
                    "to_quads": rep["mesh_distance_max"], "bulging": rep["patches_bulging"],
                    "gap": rep["boundary_gap_max"], "to_truth": [d[k] for k in ("mean", "p99", "max")],
                    "nodes": node_times(events)})
                if a.docs and part == "fandisk":
                    os.makedirs(a.docs, exist_ok=True)
                    for pic in ("segments.png", "surfaces.png"):
                        shutil.copy(os.path.join(out, pic), os.path.join(a.docs, f"fandisk_{source}_{pic}"))
            rows.append(row)
            print(json.dumps(row), flush=True)
    json.dump(rows, open(os.path.join(a.work, "surfaces_table.json"), "w"), indent=1)
    eps, nf = hand_made_fandisk_eps()
    lines = ["| part | from | quads (all quads) | EPs | feature on quad edges | base | patches | min n.d | poles "
             "| vertex to surface max / mean (mm) | surface to quads max (mm) | bulging | border gap (mm) "
             "| surfaces to truth mean / p99 / max (mm) | wall (s) | peak (MiB) | slowest nodes (s) |",
             "|" + "---|" * 17]
    for r in rows:
        if not r["ok"]:
            lines.append(f"| {r['part']} | {r['source']} | failed: {r['error']} |" + " |" * 14)
            continue
        slow = ", ".join(f"{n} {s:.1f}" for n, s, _ in sorted(r["nodes"], key=lambda t: -t[1])[:3])
        lines.append(
            f"| {r['part']} | {r['source']} | {r['quads']} ({100 * r['quad_fraction']:.0f} %) | {r['eps']} "
            f"| {100 * r['feature_share']:.1f} % | {[round(x, 2) for x in r['base']]} | {r['patches']} "
            f"| {r['min_normal_dot']:.3f} | {r['poles']} | {r['fit_max']:.5f} / {r['fit_mean']:.5f} "
            f"| {r['to_quads']:.3f} | {r['bulging']} | {r['gap']:.3f} "
            f"| {' / '.join(f'{x:.3f}' for x in r['to_truth'])} | {r['wall_s']} | {r['peak_mib']} | {slow} |")
    lines.append("")
    lines.append(f"The hand-made fandisk quads (`fandisk_quads.off`, {nf} quads): {eps} extraordinary points.")
    table = "\n".join(lines)
    open(os.path.join(a.work, "surfaces_table.md"), "w").write(table + "\n")
    print(table)

if __name__ == "__main__":
    main()
