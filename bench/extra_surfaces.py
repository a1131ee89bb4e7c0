#!/usr/bin/python3
"""Test surfaces the shared catalog lacks (crests, creases, steep rims), registered into
../shared/tools/surfaces.py's catalog in-process, so make_cloud.py and verify.py measure them
exactly as they measure the catalog.

  bench/extra_surfaces.py cloud  NAME --n N --seed S [--noise SIGMA] -o out.ply
  bench/extra_surfaces.py verify NAME --gcode g.ngc --tool-radius R --scallop H --chord E --json v.json
  bench/extra_surfaces.py error  NAME cloud.ply   # largest |error| / uncertainty of a denoised cloud
  bench/extra_surfaces.py model-error NAME cloud.ply [--bin build/height_field_error]
      # the same between the points: the certificate's surface model (HeightFieldModel)
  bench/extra_surfaces.py names

steepcap: a sphere cap with rim slopes from 75 to 88 degrees along an irregular outline.
holed_waves, holed_dome, slot_plane: catalog surfaces with holes (round, rectangular, a slot, one
2 mm from the outline).
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


# Patches with holes: the edge of a hole lies beyond the cloud's points around it, as the outline
# does beyond its outermost ones (measured to the holes' real edges, as verify.py measures).
def _off_circle(x, y, cx, cy, r):
    return np.hypot(x - cx, y - cy) > r


def _off_rect(x, y, cx, cy, hw, hh):
    return ~((np.abs(x - cx) <= hw) & (np.abs(y - cy) <= hh))


def _holed_waves_inside(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    return ((np.abs(x) <= 60) & (np.abs(y) <= 40) & _off_circle(x, y, -25, 10, 8) &
            _off_rect(x, y, 30, -15, 7.5, 5))


def _holed_dome_inside(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    return (np.hypot(x, y) <= 50) & _off_circle(x, y, 15, -10, 5) & _off_circle(x, y, -20, 20, 1.5)


def _slot_plane_inside(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    return ((np.abs(x) <= 50) & (np.abs(y) <= 30) & _off_rect(x, y, 0, 10, 15, 1) &
            _off_circle(x, y, 44, 0, 4))


_cat = surfaces.CATALOG
EXTRA["holed_waves"] = surfaces.Surface(
    "holed_waves", "the catalog's waves with a round hole (radius 8) and a 15 x 10 one",
    _cat["waves"].f, _cat["waves"].boundary, _holed_waves_inside)
EXTRA["holed_dome"] = surfaces.Surface(
    "holed_dome", "the catalog's dome with round holes of radius 5 and 1.5",
    _cat["dome"].f, _cat["dome"].boundary, _holed_dome_inside)
EXTRA["slot_plane"] = surfaces.Surface(
    "slot_plane", "the catalog's plane with a 30 x 2 slot and a round hole 2 mm from its edge",
    _cat["plane"].f, _cat["plane"].boundary, _slot_plane_inside)
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


def model_error(name, path, binary):
    """Largest |error| / uncertainty of the certificate's surface model (HeightFieldModel, run as
    bench/height_field_error.cpp) between the cloud's points: at 20 000 places jittered off the
    points (a third of a spacing), and for a crest 12 000 more across its top, rims included."""
    import subprocess, tempfile
    from scipy.spatial import cKDTree
    surf = surfaces.get(name)
    v = read_ply(path)
    P = np.column_stack([v["x"], v["y"], v["z"]]).astype(float)
    u = v["uncertainty"].astype(float) if "uncertainty" in v.dtype.names else np.full(len(P), 1e-4)
    spacing = float(np.median(cKDTree(P[:, :2]).query(P[:: max(1, len(P) // 5000), :2], 2)[0][:, 1]))
    rng = np.random.default_rng(0)
    q = P[rng.choice(len(P), min(20000, len(P)), replace=False), :2]
    q = q + rng.normal(0, spacing / 3, q.shape)
    if name.startswith("crest_"):
        radius, slope, angle = (float(t[1:]) for t in name.split("_")[1:4])
        t = math.radians(angle)
        band = max(3.0, 2 * radius)
        s_ = rng.uniform(-band, band, 12000)
        w_ = np.r_[rng.uniform(-60, 60, 9000), rng.choice([-1, 1], 3000) * rng.uniform(28, 31, 3000)]
        q = np.r_[q, np.column_stack([s_ * math.cos(t) - w_ * math.sin(t), s_ * math.sin(t) + w_ * math.cos(t)])]
    q = q[surf.inside(q[:, 0], q[:, 1])]
    with tempfile.TemporaryDirectory() as d:
        np.savetxt(os.path.join(d, "cloud.txt"), np.column_stack([P, u]), fmt="%.10g")
        out = subprocess.run([binary, os.path.join(d, "cloud.txt")], check=True, capture_output=True,
                             input="\n".join("%.10g %.10g" % (a, b) for a, b in q).encode()).stdout
    ans = np.array([l.split() for l in out.decode().split("\n") if l], float)
    ok = np.isfinite(ans[:, 0])
    q, z, um = q[ok], ans[ok, 0], ans[ok, 1]
    zt, n, _, _ = surf.evaluate(q[:, 0], q[:, 1])
    err = np.abs(z - zt) * n[:, 2]
    ratio = err / np.maximum(um, 1e-12)
    i = int(np.argmax(ratio))
    return {"max_ratio": float(ratio[i]), "at": [float(q[i, 0]), float(q[i, 1])], "error": float(err[i]),
            "uncertainty": float(um[i]), "error_max": float(err.max()), "places": int(len(q)),
            "uncertainty_median": float(np.median(um)), "uncertainty_p99": float(np.percentile(um, 99))}


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
    if cmd == "model-error":
        import json
        binary = argv[argv.index("--bin") + 1] if "--bin" in argv else os.path.join(
            os.path.dirname(os.path.abspath(__file__)), "..", "build", "height_field_error")
        print(json.dumps(model_error(argv[1], argv[2], binary)))
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
