#!/usr/bin/python3
"""How far a part's sharp edges stand off a mesh made from its cloud (issue 14): the true mesh's
edges whose faces turn by more than --angle are sampled every --step mm, and each sample's
distance to the mesh is measured exactly (the nearest of the triangles that can be nearest).
Where a restored edge (mesh.sharpen) is off the part's, the part sticks out of the mesh by about
that much, and a ball kept off the mesh cuts it.

  bench/edge_distance.py MESH TRUE_MESH [--scale 50] [--angle 20] [--step 0.1] [--worst 10]

MESH is the product's (e.g. out/workpiece-cloud/mesh.ply), TRUE_MESH the part's (.off, .stl,
.obj, .ply) in its own units, multiplied by --scale into MESH's mm. Prints the distances' median,
p90, p99 and maximum, the fraction over 0.005, 0.01 and 0.02 mm, and the worst samples.
Uses ../shared/tools/verify.py's mesh reader and point-triangle distance.
"""
import argparse, os, sys

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
sys.path.insert(0, TOOLS)
import verify  # noqa: E402


def sharp_edge_samples(V, F, angle, step):
    """Points every `step` along the edges whose two faces turn by more than `angle` degrees."""
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    faces_of = {}
    for f, t in enumerate(F):
        for c in range(3):
            faces_of.setdefault(tuple(sorted((t[c], t[(c + 1) % 3]))), []).append(f)
    cos_limit = np.cos(np.radians(angle))
    out = []
    for (a, b), fs in faces_of.items():
        if len(fs) != 2 or n[fs[0]] @ n[fs[1]] > cos_limit:
            continue
        count = max(1, int(np.ceil(np.linalg.norm(V[b] - V[a]) / step)))
        t = (np.arange(count) + 0.5) / count
        out.append(V[a] + t[:, None] * (V[b] - V[a]))
    return np.concatenate(out) if out else np.zeros((0, 3))


def distances_to_mesh(Q, V, F):
    """Exact distance from each point to the triangles: every triangle whose centroid lies within
    the nearest centroid's distance plus twice the largest centroid-to-corner span is tried."""
    T = V[F]
    C = T.mean(axis=1)
    span = np.linalg.norm(T - C[:, None, :], axis=2).max()
    tree = cKDTree(C)
    near, _ = tree.query(Q)
    d = np.empty(len(Q))
    for i, q in enumerate(Q):
        cand = np.asarray(tree.query_ball_point(q, near[i] + 2 * span))
        d[i] = verify.triangle_distance(q, T[cand, 0], T[cand, 1], T[cand, 2]).min()
    return d


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("true_mesh")
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--angle", type=float, default=20.0, help="degrees: sharper true edges are sampled")
    ap.add_argument("--step", type=float, default=0.1, help="mm between samples along an edge")
    ap.add_argument("--worst", type=int, default=10, help="worst samples listed")
    a = ap.parse_args()
    V, F = verify.read_mesh(a.mesh)
    TV, TF = verify.read_mesh(a.true_mesh)
    S = sharp_edge_samples(TV * a.scale, TF, a.angle, a.step)
    if len(S) == 0:
        sys.exit("no edge of %s turns by more than %g degrees" % (a.true_mesh, a.angle))
    d = distances_to_mesh(S, V, F)
    p50, p90, p99, top = np.percentile(d, [50, 90, 99, 100])
    print("%d samples of the true edges over %g deg, distance to %s (mm): median %.4f, p90 %.4f, p99 %.4f, max %.4f"
          % (len(S), a.angle, a.mesh, p50, p90, p99, top))
    print("over 0.005 mm: %.2f %%, over 0.01: %.2f %%, over 0.02: %.2f %%"
          % tuple(100 * np.mean(d > x) for x in (0.005, 0.01, 0.02)))
    for i in np.argsort(-d)[:a.worst]:
        print("  %.4f at (%.3f, %.3f, %.3f)" % (d[i], *S[i]))


if __name__ == "__main__":
    main()
