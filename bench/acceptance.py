#!/usr/bin/python3
"""Acceptance table: every catalog surface, clean and noisy, through the shipped graphs,
measured by the independent ../shared/tools/verify.py and by the product's own post.simulate.

  bench/acceptance.py [--surfaces plane,dome,...] [--graphs zigzag,contour] [--noise 0,0.02]
                      [--n 50000] [--work /tmp/scallop-acceptance] [--docs docs/catalog]

Prints a Markdown table and writes it (plus every JSON report) under --work.
"""
import argparse, json, os, shutil, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
ALL = ["plane", "dome", "bowl", "saddle", "waves", "freeform", "canopy"]

def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, **kw)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--surfaces", default=",".join(ALL))
    ap.add_argument("--graphs", default="zigzag,contour")
    ap.add_argument("--noise", default="0,0.02")
    ap.add_argument("--n", type=int, default=50000)
    ap.add_argument("--work", default="/tmp/scallop-acceptance")
    ap.add_argument("--docs", default="", help="copy preview and scallop map PNGs here")
    ap.add_argument("--set", action="append", default=[], help="extra --set for scallop run")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rows = []
    header = ("| surface | noise | graph | passes | verify scallop max (interior) | simulate scallop max (interior) "
              "| sim/verify | gouge max | uncut | rs274 | rapids through part | efficiency L*/L | verify pass | plan s |")
    print(header)
    print("|---" * (header.count("|") - 1) + "|")
    for surface in args.surfaces.split(","):
        r = 2.0 if surface == "bowl" else 4.0
        for noise in args.noise.split(","):
            tag = f"{surface}" + ("" if float(noise) == 0 else f"_noise{noise}")
            cloud = os.path.join(args.work, tag + ".ply")
            if not os.path.exists(cloud):
                cmd = [sys.executable, os.path.join(TOOLS, "make_cloud.py"), "--surface", surface, "--n", str(args.n),
                       "--seed", "1", "-o", cloud]
                if float(noise) > 0:
                    cmd += ["--noise", noise]
                run(cmd, check=True)
            for graph in args.graphs.split(","):
                out = os.path.join(args.work, f"{tag}_{graph}")
                shutil.rmtree(out, ignore_errors=True)
                t0 = time.time()
                cmd = [os.path.join(ROOT, "build", "scallop"), "run", os.path.join(ROOT, "graphs", f"isoparametric-{graph}.json"),
                       "--input", f"cloud={cloud}", "--no-cache", "-q", "-o", out, "--set", f"tool_radius={r}",
                       "--set", "scallop_height=0.05", "--set", "chord_error=0.01"]
                for s in args.set:
                    cmd += ["--set", s]
                p = run(cmd)
                plan_s = time.time() - t0
                gcode = os.path.join(out, "gcode.ngc")
                if p.returncode != 0 or not os.path.exists(gcode):
                    err = (p.stderr.strip().splitlines() or ["?"])[-1]
                    print(f"| {surface} | {noise} | {graph} | FAILED: {err} |||||||||||", flush=True)
                    rows.append({"surface": surface, "noise": noise, "graph": graph, "error": err})
                    continue
                vj = os.path.join(out, "verify.json")
                run([sys.executable, os.path.join(TOOLS, "verify.py"), "--gcode", gcode, "--tool-radius", str(r),
                     "--scallop", "0.05", "--chord", "0.01", "--surface", surface, "--json", vj,
                     "--plot", os.path.join(out, "verify.png")])
                v = json.load(open(vj)) if os.path.exists(vj) else {"error": "no report"}
                sim = json.load(open(os.path.join(out, "report.json")))
                plan = json.load(open(os.path.join(out, "plan_report.json")))
                vs, ss = v.get("scallop_max_interior"), sim.get("scallop_max_interior")
                ratio = f"{ss / vs:.4f}" if vs and ss else "-"
                row = {"surface": surface, "noise": noise, "graph": graph, "passes": plan.get("passes"),
                       "verify": v, "simulate": sim, "plan_seconds": plan_s}
                rows.append(row)
                print(f"| {surface} | {noise} | {graph} | {plan.get('passes')} | {vs:.5f} | {ss:.5f} | {ratio} "
                      f"| {v.get('gouge_max', float('nan')):.5f} | {v.get('uncut_fraction')} | {v.get('gcode_valid')} "
                      f"| {v.get('rapids_through_part')} | {v.get('efficiency', float('nan')):.3f} | {v.get('pass')} "
                      f"| {plan_s:.1f} |", flush=True)
                if args.docs:
                    os.makedirs(args.docs, exist_ok=True)
                    for name in ("preview.png", "scallop_map.png"):
                        src = os.path.join(out, name)
                        if os.path.exists(src):
                            shutil.copy(src, os.path.join(args.docs, f"{tag}_{graph}_{name}"))
    json.dump(rows, open(os.path.join(args.work, "acceptance.json"), "w"), indent=1)

if __name__ == "__main__":
    main()
