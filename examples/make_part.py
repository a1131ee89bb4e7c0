#!/usr/bin/env python3
"""Writes examples/domed_block.stl: a small closed part to try the whole-workpiece graphs on.

A block 60 x 40 mm standing on its base (z = 0), with vertical sides 15 mm high and a domed top

    z = 15 + 3 sin(pi x / 60) sin(pi y / 40)        (mm, 0 <= x <= 60, 0 <= y <= 40)

that meets the sides along sharp edges. Triangles about 1 mm across, faces outward, as binary
STL. Pure standard library; the output is the same on every run and platform.

    python3 examples/make_part.py [-o examples/domed_block.stl] [--cell 1.0]

With --cloud N it writes instead a scan-like cloud of the same part: N points on the same
triangles, spread at random by area over every face (seeded: the same file every run), optional
Gaussian noise along each point's normal, as a binary PLY with normals (the triangles, not the
dome's formula, so that the STL is the part a judge measures the programs against):

    python3 examples/make_part.py --cloud 100000 [--noise 0.005] [--seed 1] -o domed_block.ply
"""
import argparse
import bisect
import math
import os
import random
import struct

WIDTH, DEPTH, SIDE, DOME = 60.0, 40.0, 15.0, 3.0


def top(x, y):
    return SIDE + DOME * math.sin(math.pi * x / WIDTH) * math.sin(math.pi * y / DEPTH)


def grid(corner, du, dv, nu, nv, lift=None):
    """Triangles of the nu x nv grid corner + i du / nu + j dv / nv (lift(p) moves a point), wound
    counter-clockwise around du x dv."""
    def at(i, j):
        p = [corner[k] + du[k] * i / nu + dv[k] * j / nv for k in range(3)]
        return lift(p) if lift else p
    tris = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    return tris


def part(cell):
    nx, ny, nz = round(WIDTH / cell), round(DEPTH / cell), round(SIDE / cell)
    dome = lambda p: [p[0], p[1], top(p[0], p[1])]
    tris = grid((0, 0, SIDE), (WIDTH, 0, 0), (0, DEPTH, 0), nx, ny, dome)      # top, +z
    tris += grid((0, 0, 0), (0, DEPTH, 0), (WIDTH, 0, 0), ny, nx)              # base, -z
    tris += grid((0, 0, 0), (WIDTH, 0, 0), (0, 0, SIDE), nx, nz)               # y = 0, -y
    tris += grid((0, DEPTH, 0), (0, 0, SIDE), (WIDTH, 0, 0), nz, nx)           # y = 40, +y
    tris += grid((0, 0, 0), (0, 0, SIDE), (0, DEPTH, 0), nz, ny)               # x = 0, -x
    tris += grid((WIDTH, 0, 0), (0, DEPTH, 0), (0, 0, SIDE), ny, nz)           # x = 60, +x
    return tris


def write_stl(path, tris):
    with open(path, 'wb') as f:
        f.write(b'domed block, scallop examples/make_part.py'.ljust(80, b' '))
        f.write(struct.pack('<I', len(tris)))
        for a, b, c in tris:
            u = [b[k] - a[k] for k in range(3)]
            v = [c[k] - a[k] for k in range(3)]
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            f.write(struct.pack('<12fH', *[x / length for x in n], *a, *b, *c, 0))


def cloud(tris, n, noise, seed):
    """n points (x, y, z, nx, ny, nz) on the triangles, uniform by area, with the face normals."""
    rng = random.Random(seed)
    normals, cumulative, total = [], [], 0.0
    for a, b, c in tris:
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        w = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = math.sqrt(sum(x * x for x in w))
        normals.append([x / length for x in w])
        total += 0.5 * length
        cumulative.append(total)
    points = []
    for _ in range(n):
        t = bisect.bisect_left(cumulative, rng.random() * total)
        a, b, c = tris[t]
        s, r = rng.random(), rng.random()
        if s + r > 1:
            s, r = 1 - s, 1 - r
        d = rng.gauss(0.0, noise) if noise > 0 else 0.0
        nrm = normals[t]
        points.append(tuple(a[k] + s * (b[k] - a[k]) + r * (c[k] - a[k]) + d * nrm[k] for k in range(3)) + tuple(nrm))
    return points


def write_ply(path, points):
    with open(path, 'wb') as f:
        f.write(('ply\nformat binary_little_endian 1.0\ncomment domed block, scallop examples/make_part.py\n'
                 'element vertex %d\nproperty double x\nproperty double y\nproperty double z\n'
                 'property double nx\nproperty double ny\nproperty double nz\nend_header\n' % len(points)).encode())
        for p in points:
            f.write(struct.pack('<6d', *p))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('-o', default=os.path.join(here, 'domed_block.stl'))
    ap.add_argument('--cell', type=float, default=1.0, help='triangle size, mm')
    ap.add_argument('--cloud', type=int, default=0, help='write a cloud of this many points instead (PLY)')
    ap.add_argument('--noise', type=float, default=0.0, help='the cloud: Gaussian noise along the normal, mm')
    ap.add_argument('--seed', type=int, default=1, help='the cloud: random seed')
    a = ap.parse_args()
    if a.cloud > 0:
        out = a.o if a.o != ap.get_default('o') else os.path.join(here, 'domed_block.ply')
        write_ply(out, cloud(part(a.cell), a.cloud, a.noise, a.seed))
        print('%s: %d points' % (out, a.cloud))
        return
    tris = part(a.cell)
    write_stl(a.o, tris)
    print('%s: %d triangles' % (a.o, len(tris)))


if __name__ == '__main__':
    main()
