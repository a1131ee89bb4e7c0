#!/usr/bin/python3
"""Issue 14's table: the three CAD parts of ../shared/data machined whole, from their true meshes
and from 200 000-point clouds (sigma 0 and 0.02 mm), each row's programs judged by the independent
../shared/tools/verify_part.py (bench/workpiece_verify.sh runs graph and judge; rows one after the
other: the judge's LinuxCNC interpreter runs one at a time).

  bench/workpiece_table.py [--rows fandisk-mesh,block-cloud0,...] [--work /tmp/scallop-workpiece-table]
  bench/workpiece_table.py --table-only [--work DIR]     (the table again from DIR/*/row.json)

Rows (name: part, input, settings): PART-mesh (r 2, h 0.02, e 0.005), fandisk-mesh-r4 (r 4,
h 0.05, e 0.01), PART-cloud0 (clean cloud: smooth=0 denoise=none exact_edges=true, as the third
example runs a clean cloud), PART-cloud2 (sigma 0.02: the graph's smoothing and denoising);
PART one of fandisk (x 50), block (x 5), abc (x 1000; its clouds sampled from its outer surface,
OUTER_SURFACE=1 in workpiece_verify.sh: the STL is an assembly of overlapping solids).
Columns: judge / certificate for pass, interior scallop max (and their ratio; 0.4 = 20 h is an
uncut place), interior 99th percentile, area over 1.01 h,
uncut, gouge, out of reach; setups; the flat-strip efficiency (the judge's measured area over
sqrt(8 r h), divided by the cut length); the graph's wall time, the time its last program was
written and its peak memory (the nodes' largest resident peak, --events).
"""
import argparse, glob, json, os, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SCALLOP_SHARED", os.path.join(ROOT, "..", "shared"))
PARTS = {
    "fandisk": ("data/fandisk/fandisk.off", 50),
    "block": ("data/block/block.off", 5),
    "abc": ("data/abc_00000050/00000050_80d90bfdd2e74e709956122a_trimesh_000.stl", 1000),
}
FINE = {"R": "2", "H": "0.02", "E": "0.005"}
CLEAN = "--set smooth=0 --set denoise=none --set exact_edges=true"


def row_settings(name):
    part, kind = name.split("-", 1)
    env = dict(FINE)
    extra = ""
    if kind == "mesh-r4":
        env = {"R": "4", "H": "0.05", "E": "0.01"}
    elif kind.startswith("cloud"):
        env["CLOUD_POINTS"] = "200000"
        env["NOISE"] = "0" if kind == "cloud0" else "0.02"
        if kind == "cloud0":
            extra = CLEAN
        if part == "abc":
            env["OUTER_SURFACE"] = "1"
    elif kind != "mesh":
        raise SystemExit(f"unknown row {name}")
    return part, kind, env, extra


def run_row(name, work):
    part, kind, env, extra = row_settings(name)
    mesh, scale = PARTS[part]
    out = os.path.join(work, name)
    events = os.path.join(work, name + ".events.jsonl")
    env = dict(os.environ, **env, EXTRA=f"{extra} --events {events} -q")
    t0 = time.time()
    r = subprocess.run(["bash", os.path.join(ROOT, "bench", "workpiece_verify.sh"), os.path.join(SHARED, mesh),
                        str(scale), out], env=env, capture_output=True, text=True, cwd=ROOT)
    row = {"name": name, "part": part, "input": kind, "settings": env.get("R") + "/" + env.get("H") + "/" + env.get("E"),
           "status": r.returncode, "wall_with_judge_s": round(time.time() - t0, 1)}
    if r.returncode != 0:
        lines = [l for l in r.stderr.splitlines() if "error" in l.lower() or "failed" in l.lower()]
        row["error"] = (lines[-1] if lines else r.stderr[-400:]).strip()
    row.update(graph_figures(events))
    judge, cert = os.path.join(out, "verify_part.json"), os.path.join(out, "report.json")
    if os.path.exists(judge) and os.path.exists(cert):
        row["judge"], row["cert"] = json.load(open(judge)), json.load(open(cert))
        for k in ("judge", "cert"):  # keep the figures, not the per-sample lists
            row[k] = {key: v for key, v in row[k].items() if not isinstance(v, (list, dict)) or key == "fail_reasons"}
    json.dump(row, open(os.path.join(work, name + ".row.json"), "w"), indent=1)
    return row


def graph_figures(events):
    if not os.path.exists(events):
        return {}
    start = end = programs = None
    peak = 0
    for line in open(events):
        e = json.loads(line)
        start = e["t"] if start is None else start
        end = e["t"]
        if e["event"] == "node_finish":
            peak = max(peak, e.get("peak_mib", 0) or 0)
            if e["type"] == "post.setup_programs":
                programs = e["t"]
    return {"graph_s": round(end - start, 1), "programs_s": programs and round(programs - start, 1), "peak_mib": peak}


def pct(v):
    return "–" if v is None else f"{100 * v:.3g} %"


def cell(row, key, fmt):
    j, c = row.get("judge", {}).get(key), row.get("cert", {}).get(key)
    return f"{fmt(j)} / {fmt(c)}"


def table(rows):
    out = ["| part | input (r / h / e) | setups | pass: judge / cert. | interior scallop max: judge / cert. (cert. / judge) "
           "| interior p99 | area over 1.01 h | uncut | gouge max | out of reach | L*/L (flat strips) | cut length (m) "
           "| graph s (programs written at) | peak MiB |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        head = f"| {row['part']} | {row['input']} ({row['settings']}) |"
        if "judge" not in row:
            out.append(head + f" {row.get('error', 'no result')} ||||||||||||")
            continue
        j, c = row["judge"], row["cert"]
        r, h = c["tool_radius"], c["scallop_limit"]
        measured = j.get("surface_area", 0) * (1 - j.get("base_fraction", 0) - j.get("unreachable_fraction", 0))
        eff = measured / (8 * r * h) ** 0.5 / j["cut_length"] if j.get("cut_length") else None
        jm, cm = j.get("scallop_max_interior"), c.get("scallop_max_interior")
        yes = lambda v: "yes" if v else "no"
        out.append(head + " " + " | ".join([
            str(len(json.load(open(os.path.join(os.path.dirname(row.get("_path", ".")), row["name"], "setups.json")))["setups"]))
            if os.path.exists(os.path.join(os.path.dirname(row.get("_path", ".")), row["name"], "setups.json")) else "",
            f"{yes(j.get('pass'))} / {yes(c.get('pass'))}",
            f"{jm:.5f} / {cm:.5f} ({cm / jm:.3f})" if jm and cm else f"{jm} / {cm}",
            cell(row, "scallop_p99_interior", lambda v: "–" if v is None else f"{v:.5f}"),
            cell(row, "frac_over_limit", pct), cell(row, "uncut_fraction", pct),
            cell(row, "gouge_max", lambda v: "–" if v is None else f"{v:.5g}"),
            cell(row, "unreachable_fraction", pct),
            "" if eff is None else f"{eff:.2f}",
            f"{j['cut_length'] / 1000:.1f}" if j.get("cut_length") else "",
            f"{row.get('graph_s')} ({row.get('programs_s')})", f"{row.get('peak_mib', 0):.0f}"]) + " |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", default="fandisk-mesh,fandisk-mesh-r4,block-mesh,abc-mesh,fandisk-cloud0,block-cloud0,"
                                       "abc-cloud0,fandisk-cloud2,block-cloud2,abc-cloud2")
    ap.add_argument("--work", default="/tmp/scallop-workpiece-table")
    ap.add_argument("--table-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    if not a.table_only:
        for name in a.rows.split(","):
            row = run_row(name, a.work)
            print(f"{name}: status {row['status']}, {row['wall_with_judge_s']} s", file=sys.stderr, flush=True)
    rows = []
    for name in a.rows.split(","):
        path = os.path.join(a.work, name + ".row.json")
        if os.path.exists(path):
            row = json.load(open(path))
            row["_path"] = path
            rows.append(row)
    print(table(rows))


if __name__ == "__main__":
    main()
