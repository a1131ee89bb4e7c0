#!/usr/bin/python3
"""How far a part's sharp edges stand off a mesh made from its cloud (issue 14): the true mesh's
edges whose faces turn by more than --angle are sampled every --step mm, and each sample's
distance to the mesh is measured exactly. Where a restored edge (mesh.sharpen) is off the part's,
the part sticks out of the mesh by about that much, and a ball kept off the mesh cuts it.

  bench/edge_distance.py MESH TRUE_MESH [--scale 50] [--angle 20] [--step 0.1] [--worst 10]

MESH is the product's (e.g. out/workpiece-cloud/mesh.ply), TRUE_MESH the part's (.off, .stl,
.obj, .ply) in its own units, multiplied by --scale into MESH's mm. Prints the distances' median,
p90, p99 and maximum, the fraction over 0.005, 0.01 and 0.02 mm, and the worst samples.
The reading, the sharp edges, their sampling and the exact distances are
../shared/tools/compare_mesh.py's (and mesh3d.py's), as its feature recall uses them.
"""
import argparse, os, sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
sys.path.insert(0, TOOLS)
import compare_mesh  # noqa: E402
import mesh3d  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("true_mesh")
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--angle", type=float, default=20.0, help="degrees: sharper true edges are sampled")
    ap.add_argument("--step", type=float, default=0.1, help="mm between samples along an edge")
    ap.add_argument("--worst", type=int, default=10, help="worst samples listed")
    a = ap.parse_args()
    result = compare_mesh.PolyMesh(a.mesh, 1.0)
    truth = compare_mesh.PolyMesh(a.true_mesh, a.scale).topology(a.angle)
    S = compare_mesh.sample_segments(truth.feature_segments()[0], a.step)[2]  # the pieces' midpoints
    if len(S) == 0:
        sys.exit("no edge of %s turns by more than %g degrees" % (a.true_mesh, a.angle))
    d = compare_mesh.make_index(mesh3d.Mesh(result.V, result.tris)).distance(S)
    p50, p90, p99, top = np.percentile(d, [50, 90, 99, 100])
    print("%d samples of the true edges over %g deg, distance to %s (mm): median %.4f, p90 %.4f, p99 %.4f, max %.4f"
          % (len(S), a.angle, a.mesh, p50, p90, p99, top))
    print("over 0.005 mm: %.2f %%, over 0.01: %.2f %%, over 0.02: %.2f %%"
          % tuple(100 * np.mean(d > x) for x in (0.005, 0.01, 0.02)))
    for i in np.argsort(-d)[:a.worst]:
        print("  %.4f at (%.3f, %.3f, %.3f)" % (d[i], *S[i]))


if __name__ == "__main__":
    main()
