#!/usr/bin/python3
"""The mesh table (issue 12): CAD meshes of ../shared/data sampled into clouds, meshed through
graphs/cloud-to-mesh.json with each denoising method, and measured against the true mesh by the
independent ../shared/tools/compare_mesh.py.

  bench/mesh_table.py [--parts fandisk,block,abc] [--noise 0,0.02,0.05] [--methods tgv,bilateral,none]
                      [--n 200000] [--work /tmp/scallop-mesh-table] [--docs docs/mesh]

Prints a Markdown table and writes it (with every JSON report) under --work; with --docs also
docs/mesh.md's table and the fandisk pictures. Columns: distance from the result to the truth and
back (mean, p99, max, mm); face-normal error against the nearest true face (area-weighted mean,
p95, degrees); sharp edges (of the truth's edges above 50 degrees, the fraction with a detected
feature edge within 2 spacings: recall; of the detected, the fraction near a true one: precision);
wall time of the run and of each node with its memory peak (scallop's --events).
"""
import argparse, json, os, shutil, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SCALLOP_SHARED", os.path.join(ROOT, "..", "shared"))
TOOLS = os.path.join(SHARED, "tools")
PY = "/usr/bin/python3"
# name: (true mesh, scale into mm)
PARTS = {
    "fandisk": ("data/fandisk/fandisk.off", 50),
    "block": ("data/block/block.off", 5),
    "abc": ("data/abc_00000050/00000050_80d90bfdd2e74e709956122a_trimesh_000.stl", 1000),
}

def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.stderr.write(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr[-2000:]}\n")
    return r

def node_times(events):
    rows = []
    for line in open(events):
        e = json.loads(line)
        if e["event"] == "node_finish" and e["status"] == "ok":
            rows.append((e["node"], e["seconds"], e.get("peak_mib", 0)))
    return rows

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default="fandisk,block,abc")
    ap.add_argument("--noise", default="0,0.02,0.05")
    ap.add_argument("--methods", default="tgv,bilateral,none")
    ap.add_argument("--n", type=int, default=200000)
    ap.add_argument("--work", default="/tmp/scallop-mesh-table")
    ap.add_argument("--docs", default="", help="folder for the fandisk pictures; the table goes beside it as .md")
    ap.add_argument("--set", action="append", default=[], help="extra --set for scallop run")
    ap.add_argument("--table-only", action="store_true",
                    help="no runs: the table (and --docs page) from WORK/mesh_table.json of an earlier run")
    a = ap.parse_args()
    if a.table_only:
        write_table(json.load(open(os.path.join(a.work, "mesh_table.json"))), a)
        return
    os.makedirs(a.work, exist_ok=True)
    scallop = os.path.join(ROOT, "build", "scallop")
    graph = os.path.join(ROOT, "graphs", "cloud-to-mesh.json")
    rows = []
    for part in a.parts.split(","):
        mesh_rel, scale = PARTS[part]
        truth = os.path.join(SHARED, mesh_rel)
        for noise in a.noise.split(","):
            cloud = os.path.join(a.work, f"{part}_n{noise}.ply")
            if not os.path.exists(cloud):
                run([PY, os.path.join(TOOLS, "sample_mesh.py"), "--mesh", truth, "--n", str(a.n), "--seed", "1",
                     "--scale", str(scale), "--noise", noise, "-o", cloud])
            for method in a.methods.split(","):
                out = os.path.join(a.work, f"{part}_n{noise}_{method}")
                shutil.rmtree(out, ignore_errors=True)
                events = out + ".events.jsonl"
                t0 = time.time()
                r = run([scallop, "run", graph, "--input", f"cloud={cloud}", "-o", out, "--no-cache", "-q",
                         "--events", events, "--set", f"denoise={method}"] + sum((["--set", s] for s in a.set), []))
                wall = time.time() - t0
                row = {"part": part, "noise": float(noise), "method": method, "wall_s": round(wall, 1),
                       "ok": r.returncode == 0}
                if r.returncode == 0:
                    rep = json.load(open(os.path.join(out, "reconstruct_report.json")))
                    spacing = rep["spacing"]
                    cmp_json = os.path.join(out, "compare.json")
                    cmd = [PY, os.path.join(TOOLS, "compare_mesh.py"), "--result", os.path.join(out, "mesh.ply"),
                           "--truth", truth, "--scale-truth", str(scale), "--match-distance", str(2 * spacing),
                           "--json", cmp_json]
                    if part == "fandisk":
                        cmd += ["--plot", os.path.join(out, "compare.png")]
                    run(cmd)
                    c = json.load(open(cmp_json))
                    d, n, f = c["distance"], c["normal_error_deg"], c["features"]
                    row.update({
                        "to_truth": [d["result_to_truth"][k] for k in ("mean", "p99", "max")],
                        "from_truth": [d["truth_to_result"][k] for k in ("mean", "p99", "max")],
                        "normal_mean": n["mean"], "normal_p95": n["p95"],
                        "recall": f["recall"], "precision": f["precision"],
                        "spacing": spacing, "nodes": node_times(events)})
                    if a.docs and part == "fandisk" and noise == "0.05":
                        os.makedirs(a.docs, exist_ok=True)
                        for pic in ("mesh.png", "compare.png"):
                            src = os.path.join(out, pic)
                            if os.path.exists(src):
                                shutil.copy(src, os.path.join(a.docs, f"fandisk_n{noise}_{method}_{pic}"))
                rows.append(row)
                print(json.dumps(row), flush=True)
    json.dump(rows, open(os.path.join(a.work, "mesh_table.json"), "w"), indent=1)
    write_table(rows, a)

def write_table(rows, a):
    lines = ["| part | noise (mm) | denoise | result→truth mean / p99 / max (mm) | truth→result mean / p99 / max (mm) "
             "| normal error mean / p95 (°) | sharp recall | sharp precision | wall (s) | slowest nodes: s (peak MiB) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if not r["ok"]:
            lines.append(f"| {r['part']} | {r['noise']} | {r['method']} | failed | | | | | {r['wall_s']} | |")
            continue
        fmt = lambda v: " / ".join(f"{x:.4f}" for x in v)
        slow = sorted(r["nodes"], key=lambda t: -t[1])[:3]
        nodes = ", ".join(f"{name} {s:.1f} ({m:.0f})" for name, s, m in slow)
        lines.append(f"| {r['part']} | {r['noise']} | {r['method']} | {fmt(r['to_truth'])} | {fmt(r['from_truth'])} "
                     f"| {r['normal_mean']:.2f} / {r['normal_p95']:.2f} | {r['recall']:.3f} | {r['precision']:.3f} "
                     f"| {r['wall_s']} | {nodes} |")
    table = "\n".join(lines)
    open(os.path.join(a.work, "mesh_table.md"), "w").write(table + "\n")
    print(table)

    if a.docs:
        pics = sorted(f for f in os.listdir(a.docs) if f.endswith(".png")) if os.path.isdir(a.docs) else []
        rel = os.path.basename(os.path.normpath(a.docs))
        page = [HEADER.format(n=a.n), table, "", "## The fandisk at sigma = 0.05 mm", ""]
        page += [f'<img src="{rel}/{f}" width="48%"> ' for f in pics if "n0.05" in f]
        open(os.path.normpath(a.docs) + ".md", "w").write("\n".join(page) + "\n")

HEADER = """# Meshes from point clouds: measured

Made by `bench/mesh_table.py --docs docs/mesh` (then `--table-only` to redo the page). Each CAD mesh
of `../shared/data` (fandisk ×50, block ×5, the ABC plate ×1000, in mm) sampled into {n} points by
`../shared/tools/sample_mesh.py` (seed 1, Gaussian noise sigma per axis), run through
`graphs/cloud-to-mesh.json` with each `denoise` method, and measured against the true mesh by
`../shared/tools/compare_mesh.py`: distances both ways; the face-normal error against the nearest
true face (area-weighted); of the true edges sharper than 50 degrees, the share with a detected
feature edge within 2 point spacings (recall), and of the detected, the share near a true one
(precision). Wall time is the whole run; the slowest nodes with the process's memory peak while
each ran (scallop's `--events`). Times were taken with other work on the 2 cores (the tgv rows of
2026-11-23 while a sanitizer build ran at higher priority): the README gives a quiet measurement.

"""

if __name__ == "__main__":
    main()
