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
    rows, lines = [], []
    header = ("| surface | noise | graph | passes | verify scallop max (interior) | simulate scallop max (interior) "
              "| sim/verify | gouge max | uncut | rs274 | rapids through part | efficiency L*/L | verify pass "
              "| guard: lifted (highest lift mm) | certificate: pass (gouge bound) | plan s |")
    def emit(line):
        print(line, flush=True)
        lines.append(line)
    emit(header)
    emit("|---" * (header.count("|") - 1) + "|")
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
                    emit(f"| {surface} | {noise} | {graph} | FAILED: {err} |||||||||||||")
                    rows.append({"surface": surface, "noise": noise, "graph": graph, "error": err})
                    continue
                vj = os.path.join(out, "verify.json")
                run([sys.executable, os.path.join(TOOLS, "verify.py"), "--gcode", gcode, "--tool-radius", str(r),
                     "--scallop", "0.05", "--chord", "0.01", "--surface", surface, "--json", vj,
                     "--plot", os.path.join(out, "verify.png")])
                v = json.load(open(vj)) if os.path.exists(vj) else {"error": "no report"}
                sim = json.load(open(os.path.join(out, "report.json")))
                plan = json.load(open(os.path.join(out, "plan_report.json")))
                guard_path = os.path.join(out, "guard_report.json")
                guard = json.load(open(guard_path)) if os.path.exists(guard_path) else {}
                vs, ss = v.get("scallop_max_interior"), sim.get("scallop_max_interior")
                ratio = f"{ss / vs:.4f}" if vs and ss else "-"
                row = {"surface": surface, "noise": noise, "graph": graph, "passes": plan.get("passes"),
                       "verify": v, "simulate": sim, "guard": guard, "plan_seconds": plan_s}
                rows.append(row)
                emit(f"| {surface} | {noise} | {graph} | {plan.get('passes')} | {vs:.5f} | {ss:.5f} | {ratio} "
                      f"| {v.get('gouge_max', float('nan')):.5f} | {v.get('uncut_fraction')} | {v.get('gcode_valid')} "
                      f"| {v.get('rapids_through_part')} | {v.get('efficiency', float('nan')):.3f} | {v.get('pass')} "
                      f"| {guard.get('lifted_positions', '-')} ({guard.get('highest_lift', 0):.4f}) "
                      f"| {sim.get('pass')} ({sim.get('gouge_max', float('nan')):.4f}) | {plan_s:.1f} |")
                if args.docs and float(noise) == 0:
                    os.makedirs(args.docs, exist_ok=True)
                    for name in ("preview.png", "scallop_map.png"):
                        src = os.path.join(out, name)
                        if os.path.exists(src):
                            copy_picture(src, os.path.join(args.docs, f"{tag}_{graph}_{name}"))
    json.dump(rows, open(os.path.join(args.work, "acceptance.json"), "w"), indent=1)
    if args.docs:
        write_catalog(args, lines)


def copy_picture(src, dst, width=700, colours=128):
    """Copies a PNG for the docs, at most `width` pixels wide with a `colours` palette (PIL), or as it is."""
    try:
        from PIL import Image
    except ImportError:
        shutil.copy(src, dst)
        return
    im = Image.open(src).convert("RGB")
    if im.width > width:
        im = im.resize((width, round(im.height * width / im.width)), Image.LANCZOS)
    im.quantize(colours).save(dst, optimize=True)


def write_catalog(args, table):
    """docs/catalog.md: the table and, for every clean surface and graph, the paths and the scallop map."""
    rel = os.path.basename(os.path.normpath(args.docs))
    md = ["# Catalog surfaces", "",
          "Every catalog surface of `../shared/tools/surfaces.py` (50 000 points, seed 1), through both shipped graphs: "
          "tool radius 4 mm (2 mm for the bowl), scallop 0.05 mm, chord 0.01 mm. Made by `bench/acceptance.py --docs docs/catalog`; "
          "verify.py is the independent measurement, simulate is the product's own `post.simulate`. "
          "On noisy clouds `post.simulate` reports a bound for the real surface (the scallop on the "
          "denoised cloud plus its uncertainty, see README \"Noisy clouds\"), hence above verify.py.", ""] + table + [""]
    for surface in args.surfaces.split(","):
        md.append(f"## {surface}")
        md.append("")
        for graph in args.graphs.split(","):
            pre, heat = f"{rel}/{surface}_{graph}_preview.png", f"{rel}/{surface}_{graph}_scallop_map.png"
            if os.path.exists(os.path.join(os.path.dirname(os.path.normpath(args.docs)), pre)):
                md.append(f"{graph}: paths and scallop map")
                md.append("")
                md.append(f'<img src="{pre}" width="48%"> <img src="{heat}" width="48%">')
                md.append("")
    open(os.path.join(os.path.dirname(os.path.normpath(args.docs)), "catalog.md"), "w").write("\n".join(md) + "\n")

if __name__ == "__main__":
    main()
