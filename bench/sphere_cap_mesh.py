#!/usr/bin/env python3
"""A fine triangle mesh of a sphere cap, the true surface of ../shared/data's hemisphere.

The cap of the sphere of radius R about the origin, from its pole down to the polar angle
--max-angle (degrees), rings about --spacing mm apart along the surface, written as a binary PLY
for verify.py --mesh. Facets of spacing s lie at most s^2 / (8 R) inside the sphere (5.6e-5 mm
for the defaults).
  bench/sphere_cap_mesh.py -o cap.ply [--radius 50] [--max-angle 75] [--spacing 0.15]
"""
import argparse

import numpy as np


def cap_mesh(radius, max_angle_deg, spacing):
    theta_max = np.radians(max_angle_deg)
    rings = int(np.ceil(radius * theta_max / spacing))
    verts = [np.array([0.0, 0.0, radius])]
    ring_of = [[0]]
    for i in range(1, rings + 1):
        theta = theta_max * i / rings
        m = max(6, int(np.ceil(2 * np.pi * radius * np.sin(theta) / spacing)))
        phi = 2 * np.pi * np.arange(m) / m
        start = len(verts)
        verts.extend(radius * np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                        np.full(m, np.cos(theta))], axis=1))
        ring_of.append(list(range(start, start + m)))
    faces = []
    for a, b in zip(ring_of, ring_of[1:]):  # each band between two rings, by merging their angles
        na, nb = len(a), len(b)
        if na == 1:
            faces.extend((a[0], b[j], b[(j + 1) % nb]) for j in range(nb))
            continue
        ia = ib = 0
        while ia < na or ib < nb:
            if ib < nb and (ia >= na or (ib + 1) / nb <= (ia + 1) / na):
                faces.append((a[ia % na], b[ib % nb], b[(ib + 1) % nb]))
                ib += 1
            else:
                faces.append((a[ia % na], b[ib % nb], a[(ia + 1) % na]))
                ia += 1
    V, F = np.array(verts), np.array(faces)
    up = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2] > 0
    F[~up] = F[~up][:, [0, 2, 1]]
    return V, F


def write_ply(path, V, F):
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(V)}\nproperty double x\n"
                 f"property double y\nproperty double z\nelement face {len(F)}\n"
                 "property list uchar int vertex_indices\nend_header\n").encode())
        f.write(V.astype("<f8").tobytes())
        rec = np.zeros(len(F), dtype=[("n", "u1"), ("i", "<i4", 3)])
        rec["n"], rec["i"] = 3, F
        f.write(rec.tobytes())


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--radius", type=float, default=50.0)
    ap.add_argument("--max-angle", type=float, default=75.0)
    ap.add_argument("--spacing", type=float, default=0.15)
    a = ap.parse_args()
    V, F = cap_mesh(a.radius, a.max_angle, a.spacing)
    write_ply(a.output, V, F)
    print(f"{a.output}: {len(V)} vertices, {len(F)} triangles")
