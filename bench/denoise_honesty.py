#!/usr/bin/python3
"""How honest and how fast cloud.denoise is on noisy clouds with exact surfaces: the seven catalog
surfaces and eight crests of bench/extra_surfaces.py (50 000 points, sigma 0.02 mm, seed 1), each
through the shipped graphs' steps up to the denoising (read, clean, trim, normals, height field,
denoise). For each: the denoising node's time, its shared-fit centres, the median and 99th
percentile of the uncertainty delta, and the largest |error| / delta over the denoised points
against the exact surface (bench/extra_surfaces.py error; the certificate rests on it being <= 1).

  bench/denoise_honesty.py [--surfaces plane,...] [--work /tmp/scallop-denoise-honesty]
                           [--build DIR] [--set denoise.share=0]...
"""
import argparse, json, os, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import extra_surfaces  # noqa: E402  (registers the crests into the shared catalog)
import numpy as np  # noqa: E402

SURFACES = ["plane", "dome", "bowl", "saddle", "waves", "freeform", "canopy",
            "crest_r1_a0.7_t0", "crest_r3_a0.7_t0", "crest_r1_a0.3_t30", "crest_r3_a0.3_t0",
            "crest_r10_a0.3_t30", "crest_r10_a0.7_t0", "crest_r1_a0.7_t30", "crest_r3_a0.7_t30"]
STEPS = ["read", "clean", "trim", "normals", "height_field", "denoise"]


def denoise_graph(work):
    """The zig-zag graph's steps up to the denoising, with the denoised cloud and report as outputs."""
    g = json.load(open(os.path.join(ROOT, "graphs", "isoparametric-zigzag.json")))
    g["nodes"] = [n for n in g["nodes"] if n["id"] in STEPS]
    g["outputs"] = {"denoised": "denoise.cloud", "denoise_report": "denoise.report"}
    g["inputs"]["cloud"].pop("default", None)
    path = os.path.join(work, "denoise-only.json")
    json.dump(g, open(path, "w"), indent=1)
    return path


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--surfaces", default=",".join(SURFACES))
    ap.add_argument("--work", default="/tmp/scallop-denoise-honesty")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--set", action="append", default=[], help="extra --set for scallop run")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    graph = denoise_graph(args.work)
    print("| cloud | denoise s | centres | median delta (mm) | p99 delta (mm) | largest abs(error)/delta | at (x, y) |")
    print("|---|---|---|---|---|---|---|")
    worst = 0.0
    for name in args.surfaces.split(","):
        cloud = os.path.join(args.work, f"{name}_noise0.02.ply")
        if not os.path.exists(cloud):
            subprocess.run([sys.executable, os.path.join(ROOT, "bench", "extra_surfaces.py"), "cloud", name,
                            "--n", "50000", "--seed", "1", "--noise", "0.02", "-o", cloud],
                           check=True, capture_output=True)
        out = os.path.join(args.work, name)
        events = out + ".events"
        cmd = [os.path.join(args.build, "scallop"), "run", graph, "--input", f"cloud={cloud}", "--no-cache", "-q",
               "-o", out, "--events", events]
        for s in args.set:
            cmd += ["--set", s]
        subprocess.run(cmd, check=True, capture_output=True)
        seconds = next(e["seconds"] for e in map(json.loads, open(events))
                       if e["event"] == "node_finish" and e["node"] == "denoise")
        report = json.load(open(os.path.join(out, "denoise_report.json")))
        delta = extra_surfaces.read_ply(os.path.join(out, "denoised.ply"))["uncertainty"].astype(float)
        e = extra_surfaces.error_ratio(name, os.path.join(out, "denoised.ply"))
        worst = max(worst, e["max_ratio"])
        print(f"| {name} | {seconds:.2f} | {report.get('shared_centres', 0)} | {np.median(delta):.5f} | "
              f"{np.percentile(delta, 99):.5f} | {e['max_ratio']:.3f} | ({e['at'][0]:.2f}, {e['at'][1]:.2f}) |",
              flush=True)
    print(f"\nlargest |error| / delta over these clouds: {worst:.3f}")


if __name__ == "__main__":
    main()
