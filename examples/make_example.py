#!/usr/bin/env python3
"""Writes examples/freeform_patch.ply: a small free-form height-field patch to try scallop on.

8000 points sampled uniformly at random (fixed seed) on

    z = 4 sin(x / 12) cos(y / 15) + 0.002 x^2        (mm)

over the rectangle 0 <= x <= 80, 0 <= y <= 60 mm, with Gaussian noise of 0.005 mm added to z,
as binary little-endian PLY with float x y z. Pure standard library; the output is the same on
every run and platform (random.Random with a fixed seed, IEEE doubles rounded to float32).

    python3 examples/make_example.py [-o examples/freeform_patch.ply] [--n 8000] [--seed 7]
"""
import argparse
import math
import os
import random
import struct


def height(x, y):
    return 4.0 * math.sin(x / 12.0) * math.cos(y / 15.0) + 0.002 * x * x


def sample(n, seed, noise=0.005, width=80.0, depth=60.0):
    rng = random.Random(seed)
    points = []
    for _ in range(n):
        x = rng.uniform(0.0, width)
        y = rng.uniform(0.0, depth)
        points.append((x, y, height(x, y) + rng.gauss(0.0, noise)))
    return points


def write_ply(path, points, comment):
    header = (
        "ply\n"
        "format binary_little_endian 1.0\n"
        f"comment {comment}\n"
        f"element vertex {len(points)}\n"
        "property float x\n"
        "property float y\n"
        "property float z\n"
        "end_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(b"".join(struct.pack("<3f", *p) for p in points))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=os.path.join(here, "freeform_patch.ply"))
    ap.add_argument("--n", type=int, default=8000, help="number of points")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    pts = sample(args.n, args.seed)
    write_ply(args.output, pts,
              "scallop example: z = 4 sin(x/12) cos(y/15) + 0.002 x^2 over 80 x 60 mm, "
              f"noise 0.005 mm, n {args.n}, seed {args.seed}")
    print(f"{args.output}: {len(pts)} points")


if __name__ == "__main__":
    main()
