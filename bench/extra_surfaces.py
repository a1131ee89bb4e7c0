#!/usr/bin/python3
"""Test surfaces the shared catalog lacks (crests, creases, steep rims), registered into
../shared/tools/surfaces.py's catalog in-process, so make_cloud.py and verify.py measure them
exactly as they measure the catalog.

  bench/extra_surfaces.py cloud  NAME --n N --seed S [--noise SIGMA] -o out.ply
  bench/extra_surfaces.py verify NAME --gcode g.ngc --tool-radius R --scallop H --chord E --json v.json
  bench/extra_surfaces.py error  NAME cloud.ply   # largest |error| / uncertainty of a denoised cloud
  bench/extra_surfaces.py names

steepcap: a sphere cap with rim slopes from 75 to 88 degrees along an irregular outline.
Crest family: z = 20 - a sqrt(s^2 + c^2), s = x cos(t) + y sin(t), on a 100 x 60 rectangle: a
rounded ridge with flanks of slope a and radius c / a at its top (a hyperbola across it).
"""
import math, os, sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.environ.get("SCALLOP_TOOLS", os.path.join(ROOT, "..", "shared", "tools"))
sys.path.insert(0, TOOLS)
import surfaces  # noqa: E402


def crest(radius, slope, angle_deg):
    t = math.radians(angle_deg)
    c = radius * slope

    def f(x, y):
        s = x * math.cos(t) + y * math.sin(t)
        return 20.0 - slope * surfaces.sqrt(s * s + c * c)
    return f


EXTRA = {}
for radius in (1, 3, 10):
    for slope in (0.3, 0.7):
        for angle in (0, 30):
            name = f"crest_r{radius}_a{slope}_t{angle}"
            EXTRA[name] = surfaces.Surface(
                name, f"ridge of radius {radius} mm, flank slope {slope}, at {angle} deg",
                crest(radius, slope, angle), surfaces._rect(100, 60), surfaces._rect_inside(100, 60))
# The bundled example (examples/make_example.py): z = 4 sin(x/12) cos(y/15) + 0.002 x^2 on
# 0 <= x <= 80, 0 <= y <= 60, to measure the shipped graphs' programs on it.
EXTRA["example"] = surfaces.Surface(
    "example", "the bundled freeform_patch.ply: 4 sin(x/12) cos(y/15) + 0.002 x^2 on 80 x 60",
    lambda x, y: 4.0 * surfaces.sin(x / 12.0) * surfaces.cos(y / 15.0) + 0.002 * x * x,
    surfaces._rect(80, 60) + np.array([40.0, 30.0]),
    lambda x, y: (x >= 0) & (x <= 80) & (y >= 0) & (y <= 60))
# Steep cap: a sphere of radius 30 cut by an irregular outline rho(theta) = 30 (0.983 + 0.0165
# sin 3 theta) whose rim slopes range from 75 to 88 degrees (a face-like patch steep at its rim).
CAP_R = 30.0


def _cap_rho(theta):
    return CAP_R * (0.983 + 0.0165 * np.sin(3 * theta))


def _cap_inside(x, y):
    return np.hypot(x, y) <= _cap_rho(np.arctan2(y, x))


_th = np.arange(1440) * (2 * np.pi / 1440)
EXTRA["steepcap"] = surfaces.Surface(
    "steepcap", "sphere cap of radius 30, irregular outline, rim slopes 75-88 degrees",
    lambda x, y: surfaces.sqrt(CAP_R * CAP_R - x * x - y * y),
    np.column_stack([_cap_rho(_th) * np.cos(_th), _cap_rho(_th) * np.sin(_th)]), _cap_inside)
# Its part not steeper than 75 degrees (the disc of radius 30 sin 75 inside the outline): what
# cloud.trim_steep keeps at max_slope 75, to measure a program for the plannable part.
EXTRA["steepcap75"] = surfaces.Surface(
    "steepcap75", "steepcap up to 75 degrees: disc of radius 30 sin 75",
    lambda x, y: surfaces.sqrt(CAP_R * CAP_R - x * x - y * y),
    surfaces._circle(CAP_R * math.sin(math.radians(75))),
    lambda x, y: np.hypot(x, y) <= CAP_R * math.sin(math.radians(75)))
surfaces.CATALOG.update(EXTRA)


def read_ply(path):
    with open(path, "rb") as fh:
        head, props, n = [], [], 0
        while True:
            line = fh.readline().decode("ascii").strip()
            head.append(line)
            if line.startswith("element vertex"):
                n = int(line.split()[2])
            elif line.startswith("property"):
                props.append((line.split()[1], line.split()[2]))
            elif line == "end_header":
                break
        fmt = {"float": "<f4", "double": "<f8"}
        dt = np.dtype([(name, fmt[t]) for t, name in props])
        return np.frombuffer(fh.read(n * dt.itemsize), dtype=dt)


def error_ratio(name, path):
    """Largest |error| / uncertainty over a denoised cloud's points (error along the true normal)."""
    surf = surfaces.get(name)
    v = read_ply(path)
    x, y, z = v["x"].astype(float), v["y"].astype(float), v["z"].astype(float)
    inside = surf.inside(x, y)
    zt, n, _, _ = surf.evaluate(x[inside], y[inside])
    err = np.abs(z[inside] - zt) * n[:, 2]
    u = v["uncertainty"].astype(float)[inside]
    ratio = err / np.maximum(u, 1e-12)
    i = int(np.argmax(ratio))
    return {"max_ratio": float(ratio[i]), "at": [float(x[inside][i]), float(y[inside][i])],
            "error": float(err[i]), "uncertainty": float(u[i]), "error_max": float(err.max()),
            "uncertainty_median": float(np.median(u))}


def main(argv):
    cmd = argv[0]
    if cmd == "names":
        print("\n".join(EXTRA))
        return 0
    if cmd == "cloud":
        import make_cloud
        name = argv[1]
        return make_cloud.main(["--surface", name] + argv[2:])
    if cmd == "verify":
        import verify
        return verify.main(["--surface", argv[1]] + argv[2:])
    if cmd == "error":
        import json
        print(json.dumps(error_ratio(argv[1], argv[2])))
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
