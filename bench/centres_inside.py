#!/usr/bin/env python3
"""Are a program's ball centres inside the part? A check of verify_part.py's gouge and rapids.

verify_part.py signs its distances by the angle-weighted pseudo-normal of the nearest face, edge or
vertex, which is exact on a closed mesh wound consistently and without folds. The block's OFF has
65 edges whose faces fold back onto each other (normals more than 150 degrees apart); near them
the sign can flip. This tool asks the generalized winding number instead (Jacobson et al. 2013:
the solid angle the mesh subtends, over 4 pi; 1 inside, 0 outside, whatever the folds).

  bench/centres_inside.py MESH.off SCALE OUT SETUP R [--rapids] [--step MM]

OUT is a scallop output folder (setups.json and the programs it names), SETUP the index of a setup
in setups.json (0 first), R the tool radius. Every feed move (or, with --rapids, every rapid after
the first two lines of motion, which start from the interpreter's origin) is sampled every --step
mm (0.5), the ball centres mapped back to the part (tip + R z, then R^T (m - t)), and the number
of centres with winding number > 0.5 printed, with the first few.
"""
import argparse, json, re
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("mesh"); ap.add_argument("scale", type=float); ap.add_argument("out")
ap.add_argument("setup", type=int); ap.add_argument("r", type=float)
ap.add_argument("--rapids", action="store_true"); ap.add_argument("--step", type=float, default=0.5)
a = ap.parse_args()

words = open(a.mesh).read().split()
if words[0] != "OFF": raise SystemExit("an OFF mesh is needed")
nv, nf = int(words[1]), int(words[2])
V = np.array(words[4:4 + 3 * nv], float).reshape(nv, 3) * a.scale
F, i = [], 4 + 3 * nv
for _ in range(nf):
    k = int(words[i]); F.append([int(x) for x in words[i + 1:i + 1 + k]]); i += 1 + k
F = np.array(F)
if F.shape[1] != 3: raise SystemExit("a triangle mesh is needed")
A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]

setup = json.load(open(a.out + "/setups.json"))["setups"][a.setup]
M = np.array(setup["part_to_machine"]); R, t = M[:, :3], M[:, 3]
kind = "G0" if a.rapids else "G1"
pos, centres, motions = np.zeros(3), [], 0
for line in open(a.out + "/" + setup["gcode"]):
    words = line.split()
    if not words or words[0] not in ("G0", "G1"): continue  # G17 and the like are not motions
    motions += 1
    new = pos.copy()
    for ax, val in re.findall(r"([XYZ])(-?[\d.]+)", line): new["XYZ".index(ax)] = float(val)
    if words[0] == kind and not (a.rapids and motions <= 2):
        n = max(1, int(np.ceil(np.linalg.norm(new - pos) / a.step)))
        centres += [pos + s * (new - pos) for s in np.linspace(0, 1, n + 1)]
    pos = new
P = (np.array(centres) + [0, 0, a.r] - t) @ R

def winding(p):  # p: (m, 3) -> (m,)
    x, y, z = A[None] - p[:, None], B[None] - p[:, None], C[None] - p[:, None]
    lx, ly, lz = (np.linalg.norm(q, axis=2) for q in (x, y, z))
    det = np.einsum("pij,pij->pi", x, np.cross(y, z))
    den = lx * ly * lz + np.einsum("pij,pij->pi", x, y) * lz + np.einsum("pij,pij->pi", y, z) * lx \
        + np.einsum("pij,pij->pi", z, x) * ly
    return np.arctan2(det, den).sum(axis=1) / (2 * np.pi)

w = np.concatenate([winding(P[k:k + 64]) for k in range(0, len(P), 64)])
inside = np.where(w > 0.5)[0]
print(f"{setup['name']}: {len(P)} ball centres along its {'rapids' if a.rapids else 'feed moves'}, {len(inside)} inside the part")
for k in inside[:5]: print("  inside:", np.round(P[k], 3), "winding", round(float(w[k]), 3))
