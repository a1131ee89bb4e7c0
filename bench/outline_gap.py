#!/usr/bin/python3
"""How far a catalog surface's true outline lies beyond the boundary loop the product finds in
its cloud (issue 10, the rim): what verify.py's whole patch counts and the certificate does not.

  bench/outline_gap.py graph GRAPH.json OUT_GRAPH.json   # the graph, also writing den.ply
                                                         # (the denoised cloud) and loops.bin
  scallop run OUT_GRAPH.json --input cloud=CLOUD.ply -o RUN ...
  bench/outline_gap.py measure SURFACE RUN [--step 0.05]

Samples the true outline (../shared/tools/surfaces.py) every --step mm and prints the distance
from those samples to the cloud's outer loop (median, p90, p99, max), the share of them inside
the loop, and the cloud's median nearest-neighbour spacing in xy.
"""
import argparse, json, os, struct, sys

import numpy as np
from matplotlib.path import Path
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
sys.path.insert(0, TOOLS)
import surfaces  # noqa: E402


def make_graph(src, dst):
    g = json.load(open(src))
    g["outputs"]["loops"] = "loops.loops"
    g["nodes"].append({"id": "write_denoised", "type": "io.write_cloud", "inputs": {"cloud": "denoise.cloud"},
                       "params": {"path": "den.ply", "binary": False}})
    json.dump(g, open(dst, "w"), indent=1)


def read_run(run):
    """The outer loop's xy polygon and the denoised points (loops.bin: u64 loop count, then per
    loop a u64 length and int32 point indices)."""
    b = open(os.path.join(run, "loops.bin"), "rb").read()
    off = 8
    m = struct.unpack_from("<Q", b, off)[0]
    outer = np.array(struct.unpack_from("<%di" % m, b, off + 8))
    lines = open(os.path.join(run, "den.ply")).read().split("\n")
    start = lines.index("end_header") + 1
    pts = np.array([[float(v) for v in l.split()[:3]] for l in lines[start:] if l.strip()])
    return pts[outer, :2], pts


def measure(name, run, step):
    poly, pts = read_run(run)
    b = np.asarray(surfaces.get(name).boundary)
    c = np.roll(b, -1, axis=0)
    samples = []
    for k in range(len(b)):
        m = max(1, int(np.ceil(np.linalg.norm(c[k] - b[k]) / step)))
        samples.append(b[k] + (np.arange(m) / m)[:, None] * (c[k] - b[k]))
    T = np.vstack(samples)
    a, ab = poly, np.roll(poly, -1, axis=0) - poly
    ab2 = (ab * ab).sum(1)
    tree = cKDTree(poly)
    D = np.empty(len(T))
    for i, p in enumerate(T):  # the loop's edges at its vertices nearest p, and the ones before them
        _, ii = tree.query(p, 8)
        ii = np.unique(np.concatenate([ii, (ii - 1) % len(poly)]))
        t = np.clip(((p - a[ii]) * ab[ii]).sum(1) / ab2[ii], 0, 1)
        D[i] = np.min(np.linalg.norm(a[ii] + t[:, None] * ab[ii] - p, axis=1))
    inside = Path(poly).contains_points(T)
    nn, _ = cKDTree(pts[:, :2]).query(pts[:, :2], 2)
    print("%s: true outline from the cloud's loop: median %.3f p90 %.3f p99 %.3f max %.3f mm; "
          "inside the loop %.1f %%; xy spacing (median) %.3f mm"
          % (name, np.median(D), np.percentile(D, 90), np.percentile(D, 99), D.max(), 100 * inside.mean(),
             np.median(nn[:, 1])))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("graph")
    g.add_argument("graph")
    g.add_argument("out")
    m = sub.add_parser("measure")
    m.add_argument("surface")
    m.add_argument("run")
    m.add_argument("--step", type=float, default=0.05)
    a = ap.parse_args()
    if a.cmd == "graph":
        make_graph(a.graph, a.out)
    else:
        measure(a.surface, a.run, a.step)


if __name__ == "__main__":
    main()
