#!/usr/bin/env python3
"""How far the balls of a whole-part run stand off a mesh: the part (what stock they leave above
it) or the envelope's outer mesh (whether they touch what they were kept off).

  bench/ball_standoff.py MESH SCALE OUT R [--cylinder CX,CY,R0,R1,Z0,Z1] [--step MM]

OUT is a scallop output folder (setups.json and the programs it names), R the tool radius. Every
feed move is sampled every --step mm (0.2), the ball centres mapped back to the part's frame
(tip + R z, then R^T (m - t)), and each centre's distance to MESH (times SCALE) less R printed as
percentiles, per setup and in all: about 0 where the ball touches the mesh, the stock left under
it where it stands off. --cylinder keeps the centres whose distance from the vertical axis through
(CX, CY) lies in [R0, R1] and whose z lies in [Z0, Z1] (a boss's side). --rapids samples the rapid
moves (G0, from where the program's position is known) instead of the feed moves: how near the
rapids come to the mesh, unsigned (a rapid that starts above the part and never comes nearer than
R has not entered it). --into TOL also lists,
per setup, the centres nearer MESH than R - TOL (a ball into the part: a gouge), gathered within
1 mm of each other, each group's count and deepest centre in the part's frame. Needs ../shared/tools
(mesh3d.py) beside the repository.
"""
import argparse, json, os, re, sys
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "tools"))
import mesh3d  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("mesh"); ap.add_argument("scale", type=float); ap.add_argument("out"); ap.add_argument("r", type=float)
ap.add_argument("--cylinder"); ap.add_argument("--step", type=float, default=0.2)
ap.add_argument("--into", type=float)
ap.add_argument("--rapids", action="store_true")
a = ap.parse_args()

V, F, _ = mesh3d.load_mesh(a.mesh, a.scale)
index = mesh3d.MeshIndex(mesh3d.Mesh(V, F), 2.0)
keep = [float(x) for x in a.cylinder.split(",")] if a.cylinder else None
every = []
for setup in json.load(open(os.path.join(a.out, "setups.json")))["setups"]:
    M = np.array(setup["part_to_machine"]); R, t = M[:, :3], M[:, 3]
    pos, centres = np.full(3, np.nan), []  # unknown until the program sets it
    for line in open(os.path.join(a.out, setup["gcode"])):
        words = line.split()
        if not words or words[0] not in ("G0", "G1"): continue
        new = pos.copy()
        for ax, val in re.findall(r"([XYZ])(-?[\d.]+)", line): new["XYZ".index(ax)] = float(val)
        if words[0] == ("G0" if a.rapids else "G1") and not np.isnan(pos).any():
            n = max(1, int(np.ceil(np.linalg.norm(new - pos) / a.step)))
            centres += [pos + s * (new - pos) for s in np.linspace(0, 1, n + 1)]
        pos = new
    if not centres: continue
    P = (np.array(centres) + [0, 0, a.r] - t) @ R
    if keep:
        cx, cy, r0, r1, z0, z1 = keep
        rr = np.hypot(P[:, 0] - cx, P[:, 1] - cy)
        P = P[(rr >= r0) & (rr <= r1) & (P[:, 2] >= z0) & (P[:, 2] <= z1)]
    if len(P) < 100: continue
    d = index.distance(P, cap=5.0)
    d = np.where(np.isfinite(d), d, 5.0) - a.r  # beyond the cap: 5 mm
    every.append(d)
    if a.into is not None:
        deep = np.flatnonzero(d < -a.into)
        groups = []  # [count, depth, centre]
        for i in deep[np.argsort(d[deep])]:
            for g in groups:
                if np.linalg.norm(P[i] - g[2]) <= 1.0: g[0] += 1; break
            else: groups.append([1, -d[i], P[i]])
        for count, depth, c in groups:
            print("  %s: %d centres up to %.4f mm into the mesh near (%.2f, %.2f, %.2f)" % (setup["name"], count, depth, *c))
    print("%s: %d centres, standoff least %.4f, p1 / p10 / p50 / p90 / p99 %s mm" % (
        setup["name"], len(d), d.min(), " / ".join("%.4f" % x for x in np.percentile(d, [1, 10, 50, 90, 99]))))
if every:
    d = np.concatenate(every)
    print("all: %d centres, standoff least %.4f, p1 / p10 / p50 / p90 / p99 %s mm; more than 0.01 mm off: %.1f %%, 0.02: %.1f %%" % (
        len(d), d.min(), " / ".join("%.4f" % x for x in np.percentile(d, [1, 10, 50, 90, 99])), 100 * (d > 0.01).mean(), 100 * (d > 0.02).mean()))
