#!/usr/bin/python3
"""A floor beside a steep wall, the commonest shape a machinist finishes, from a cloud: planned
with the shipped zig-zag graph (the wall trimmed at the default max_slope 75 and handed on as
left_out), then measured against the exact part.

  SCALLOP_TOOLS=../shared/tools /usr/bin/python3 bench/floor_wall.py [--height 10] [--build build] [--work /tmp/floor_wall]

The part: a 43 x 30 mm plate, flat (z = 0) to x = 40, a wall rising `height` mm over height / 10
mm in x (84 degrees), a ledge on top to x = 43. The cloud: 30 000 points uniform in xy and the
wall sampled by its area (600 points per mm of height), seed 1.

Prints: the certificate's verdict and figures, what it reports as not reachable beside the wall,
the nearest any ball comes to the exact floor and wall inside the part (every G-code move sampled
every 0.02 mm, rs274 -g reading the program), and verify.py on the floor the ball reaches (the
true plane from x = 0 to the start of the reported band, as a mesh).
"""
import argparse, json, os, re, subprocess, sys

import numpy as np


def make_cloud(path, height, seed=1):
    rng = np.random.default_rng(seed)
    width = height / 10
    x = rng.uniform(0, 43, 30000)
    y = rng.uniform(0, 30, 30000)
    m = int(600 * height)
    t = rng.uniform(0, 1, m)
    X = np.r_[x, 40 + width * t]
    Y = np.r_[y, rng.uniform(0, 30, m)]
    Z = height * np.clip((X - 40) / width, 0, 1)
    P = np.c_[X, Y, Z]
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
                "property double z\nend_header\n" % len(P))
        np.savetxt(f, P, fmt="%.6f")


def tool_positions(gcode):
    """Tool-tip positions along every move, sampled every 0.02 mm (rs274 -g's canonical moves)."""
    out = subprocess.run(["rs274", "-g", gcode], capture_output=True, text=True).stdout
    pos, pts = None, []
    for line in out.splitlines():
        m = re.search(r"STRAIGHT_(?:FEED|TRAVERSE)\(\s*([-\d.e+]+),\s*([-\d.e+]+),\s*([-\d.e+]+)", line)
        if not m:
            continue
        new = np.array([float(v) for v in m.groups()])
        if pos is not None:
            n = max(2, int(np.linalg.norm(new - pos) / 0.02))
            pts.extend(pos + (new - pos) * t for t in np.linspace(0, 1, n))
        pos = new
    return np.array(pts)


def distance_to_part(cx, cz, height):
    """Distance in xz from ball centres to the exact floor, wall and ledge."""
    prof = np.array([[-100, 0], [40, 0], [40 + height / 10, height], [200, height]])
    best = np.full(cx.shape, np.inf)
    for (ax, az), (bx, bz) in zip(prof[:-1], prof[1:]):
        dx, dz = bx - ax, bz - az
        t = np.clip(((cx - ax) * dx + (cz - az) * dz) / (dx * dx + dz * dz), 0, 1)
        best = np.minimum(best, np.hypot(cx - (ax + t * dx), cz - (az + t * dz)))
    return best


def floor_mesh(path, x1):
    xs, ys = np.linspace(0, x1, int(x1) + 1), np.linspace(0, 30, 31)
    nx = len(xs)
    with open(path, "w") as f:
        for y in ys:
            for x in xs:
                f.write("v %g %g 0\n" % (x, y))
        for j in range(len(ys) - 1):
            for i in range(nx - 1):
                a = j * nx + i + 1
                f.write("f %d %d %d\nf %d %d %d\n" % (a, a + 1, a + nx + 1, a, a + nx + 1, a + nx))


def main(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("--height", type=float, default=10)
    ap.add_argument("--build", default=os.path.join(os.path.dirname(__file__), "..", "build"))
    ap.add_argument("--work", default="/tmp/floor_wall")
    a = ap.parse_args(argv)
    tools = os.environ.get("SCALLOP_TOOLS", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "tools"))
    os.makedirs(a.work, exist_ok=True)
    cloud, out = os.path.join(a.work, "wall.ply"), os.path.join(a.work, "out")
    make_cloud(cloud, a.height)
    graph = os.path.join(os.path.dirname(__file__), "..", "graphs", "isoparametric-zigzag.json")
    run = subprocess.run([os.path.join(a.build, "scallop"), "run", graph, "--input", "cloud=" + cloud,
                          "--no-cache", "-q", "-o", out], capture_output=True, text=True)
    print("scallop exit", run.returncode)
    if not os.path.exists(os.path.join(out, "report.json")):
        print(run.stdout + run.stderr)
        return 1
    rep = json.load(open(os.path.join(out, "report.json")))
    print("certificate:", "pass" if rep["pass"] else "FAIL", {k: rep[k] for k in ("scallop_max", "gouge_max", "uncut_fraction")},
          rep["fail_reasons"])
    band = rep.get("beside_left_out", {})
    print("not reachable beside the wall:", band)
    tips = tool_positions(os.path.join(out, "gcode.ngc"))
    centres = tips + np.array([0, 0, rep["tool_radius"]])
    inside = (centres[:, 1] >= 0) & (centres[:, 1] <= 30) & (centres[:, 0] >= 0)
    d = distance_to_part(centres[inside, 0], centres[inside, 2], a.height)
    i = np.argmin(d)
    print("nearest ball centre to the exact part, inside it: r - %.4f mm at (%.2f, %.2f, %.2f)" %
          (rep["tool_radius"] - d[i], *centres[inside][i]))
    if band.get("min"):
        mesh = os.path.join(a.work, "floor_reached.obj")
        floor_mesh(mesh, band["min"][0])
        vj = os.path.join(a.work, "verify.json")
        subprocess.run([sys.executable, os.path.join(tools, "verify.py"), "--gcode", os.path.join(out, "gcode.ngc"),
                        "--tool-radius", str(rep["tool_radius"]), "--scallop", str(rep["scallop_limit"]),
                        "--chord", str(rep["chord_limit"]), "--mesh", mesh, "--json", vj], capture_output=True)
        v = json.load(open(vj))
        print("verify.py on the floor to x = %.2f:" % band["min"][0],
              {k: v[k] for k in ("pass", "scallop_max", "gouge_max", "uncut_fraction", "efficiency")})
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
