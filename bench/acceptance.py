#!/usr/bin/python3
"""Acceptance table: every catalog surface, clean and noisy, through the shipped graphs,
measured by the independent ../shared/tools/verify.py and by the product's own post.simulate.

  bench/acceptance.py [--surfaces plane,dome,...] [--graphs zigzag,contour] [--noise 0,0.02]
                      [--n 50000] [--work /tmp/scallop-acceptance] [--docs docs/catalog]
                      [--set NAME=VALUE]... [--build DIR]

Surfaces are the shared catalog's and bench/extra_surfaces.py's (the crest family). Prints a
Markdown table and writes it (plus every JSON report) under --work. Columns: verify.py's scallop
maximum over the whole patch (rim included) and the interior, gouge and uncut area; the
certificate's (post.simulate's) whole-patch and interior scallop bounds and gouge bound, its
verdict, and whether it agrees with verify.py's (or is the stricter: "stricter" when it fails a
program verify.py passes, "NO" when it passes one verify.py fails); the largest |error| /
uncertainty over the denoised cloud's points against the exact surface.
"""
import argparse, json, os, shutil, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
EXTRA = os.path.join(ROOT, "bench", "extra_surfaces.py")
ALL = ["plane", "dome", "bowl", "saddle", "waves", "freeform", "canopy"]
PY = "/usr/bin/python3"

def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, **kw)

def graph_with_denoised(graph, work):
    """The shipped graph with the denoised cloud as one more output (for |error| / uncertainty)."""
    name = graph if os.path.exists(os.path.join(ROOT, "graphs", f"{graph}.json")) else f"isoparametric-{graph}"
    j = json.load(open(os.path.join(ROOT, "graphs", f"{name}.json")))
    j["outputs"]["denoised"] = "denoise.cloud"
    j["inputs"]["cloud"].pop("default", None)
    path = os.path.join(work, f"{name}-denoised.json")
    json.dump(j, open(path, "w"), indent=1)
    return path

def verdict(cert, ver):
    if cert is None or ver is None:
        return "-"
    if cert == ver:
        return "yes"
    return "stricter" if ver and not cert else "NO"

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--surfaces", default=",".join(ALL))
    ap.add_argument("--graphs", default="zigzag,contour")
    ap.add_argument("--noise", default="0,0.02")
    ap.add_argument("--n", type=int, default=50000)
    ap.add_argument("--work", default="/tmp/scallop-acceptance")
    ap.add_argument("--docs", default="", help="copy preview and scallop map PNGs here")
    ap.add_argument("--set", action="append", default=[], help="extra --set for scallop run")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"),
                    help="where scallop and height_field_error are (a copy lets the build go on meanwhile)")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rows, lines = [], []
    header = ("| surface | noise | graph | passes | verify scallop max: whole (interior) | gouge max | uncut "
              "| certificate scallop bound: whole (interior) | gouge bound | certificate | verify pass "
              "| agree | max abs(error)/uncertainty: points (between) | efficiency L*/L | rs274 | rapids through part "
              "| guard: lifted (highest lift mm) | plan s |")
    def emit(line):
        print(line, flush=True)
        lines.append(line)
    emit(header)
    emit("|---" * (header.count("|") - 1) + "|")
    for surface in args.surfaces.split(","):
        extra = not surface in ALL
        r = 2.0 if surface == "bowl" else 4.0
        # the limits the graph runs with, --set included, are the limits verify.py measures against
        limits = {"scallop_height": "0.05", "chord_error": "0.01"}
        limits.update(kv.split("=", 1) for kv in args.set if kv.split("=", 1)[0] in limits)
        h, e = limits["scallop_height"], limits["chord_error"]
        for noise in args.noise.split(","):
            tag = f"{surface}" + ("" if float(noise) == 0 else f"_noise{noise}")
            cloud = os.path.join(args.work, tag + ".ply")
            if not os.path.exists(cloud):
                maker = [PY, EXTRA, "cloud", surface] if extra else [PY, os.path.join(TOOLS, "make_cloud.py"), "--surface", surface]
                cmd = maker + ["--n", str(args.n), "--seed", "1", "-o", cloud]
                if float(noise) > 0:
                    cmd += ["--noise", noise]
                run(cmd, check=True)
            for graph in args.graphs.split(","):
                out = os.path.join(args.work, f"{tag}_{graph}")
                shutil.rmtree(out, ignore_errors=True)
                t0 = time.time()
                cmd = [os.path.join(args.build, "scallop"), "run", graph_with_denoised(graph, args.work),
                       "--input", f"cloud={cloud}", "--no-cache", "-q", "-o", out, "--set", f"tool_radius={r}",
                       "--set", f"scallop_height={h}", "--set", f"chord_error={e}"]
                for s in args.set:
                    cmd += ["--set", s]
                p = run(cmd)
                plan_s = time.time() - t0
                gcode = os.path.join(out, "gcode.ngc")
                denoised = os.path.join(out, "denoised.ply")
                def error_ratio(kind="error"):
                    binary = ["--bin", os.path.join(args.build, "height_field_error")] if kind == "model-error" else []
                    e = run([PY, EXTRA, kind, surface, denoised] + binary) if os.path.exists(denoised) else None
                    return json.loads(e.stdout) if e and e.returncode == 0 and e.stdout.strip() else {}
                def ratios():
                    """|error| / uncertainty at the points and between them (the certificate's model)"""
                    a, b = error_ratio(), error_ratio("model-error")
                    return a, f"{a.get('max_ratio', float('nan')):.2f} ({b.get('max_ratio', float('nan')):.2f})", b
                if p.returncode not in (0, 3) or not os.path.exists(gcode):
                    err = (p.stderr.strip().splitlines() or ["?"])[-1]
                    point, both, between = ratios()
                    emit(f"| {surface} | {noise} | {graph} | refused: {err} |||||||||| {both} |||||")
                    rows.append({"surface": surface, "noise": noise, "graph": graph, "error": err,
                                 "error_ratio": point.get("max_ratio"), "model_error": between})
                    continue
                vj = os.path.join(out, "verify.json")
                vargs = ["--gcode", gcode, "--tool-radius", str(r), "--scallop", h, "--chord", e,
                         "--json", vj, "--plot", os.path.join(out, "verify.png")]
                run(([PY, EXTRA, "verify", surface] if extra else [PY, os.path.join(TOOLS, "verify.py"), "--surface", surface]) + vargs)
                v = json.load(open(vj)) if os.path.exists(vj) else {"error": "no report"}
                sim = json.load(open(os.path.join(out, "report.json")))
                plan = json.load(open(os.path.join(out, "plan_report.json")))
                guard_path = os.path.join(out, "guard_report.json")
                guard = json.load(open(guard_path)) if os.path.exists(guard_path) else {}
                err, both, between = ratios()
                # the whole patch: scallop <= 1.01 h everywhere on it, rim included
                vpass = bool(v.get("pass")) and (v.get("scallop_max") or 0) <= 1.01 * float(h)
                row = {"surface": surface, "noise": noise, "graph": graph, "passes": plan.get("passes"),
                       "verify": v, "simulate": sim, "guard": guard, "plan_seconds": plan_s,
                       "error_ratio": err, "model_error": between, "verify_whole_pass": vpass}
                rows.append(row)
                f = lambda x: "-" if x is None else f"{x:.5f}"
                emit(f"| {surface} | {noise} | {graph} | {plan.get('passes')} "
                     f"| {f(v.get('scallop_max'))} ({f(v.get('scallop_max_interior'))}) | {f(v.get('gouge_max'))} "
                     f"| {v.get('uncut_fraction')} | {f(sim.get('scallop_max'))} ({f(sim.get('scallop_max_interior'))}) "
                     f"| {f(sim.get('gouge_max'))} | {sim.get('pass')} | {vpass} | {verdict(sim.get('pass'), vpass)} "
                     f"| {both} | {v.get('efficiency', float('nan')):.3f} "
                     f"| {v.get('gcode_valid')} | {v.get('rapids_through_part')} "
                     f"| {guard.get('lifted_positions', '-')} ({guard.get('highest_lift', 0):.4f}) | {plan_s:.1f} |")
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
          "verify.py is the independent measurement (its whole patch reaches the true outline, its interior "
          "starts one stepover inside); the certificate is the product's own `post.simulate` (its whole "
          "patch is the cloud's outline). On noisy clouds the certificate reports bounds for the real surface "
          "(the scallop on the denoised cloud plus its uncertainty, see README \"Noisy clouds\"). "
          "\"verify pass\" here asks the whole patch too: scallop <= 1.01 h everywhere, rim included; "
          "\"agree\" says whether the certificate's verdict is verify's or the stricter; the last but "
          "few column is the largest |error| / uncertainty over the denoised cloud's points and, in "
          "brackets, between them: the certificate's surface model (`bench/extra_surfaces.py model-error`).", ""] + table + [""]
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
