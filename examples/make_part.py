#!/usr/bin/env python3
"""Writes examples/domed_block.stl: a small closed part to try the whole-workpiece graphs on.

A block 60 x 40 mm standing on its base (z = 0), with vertical sides 15 mm high and a domed top

    z = 15 + 3 sin(pi x / 60) sin(pi y / 40)        (mm, 0 <= x <= 60, 0 <= y <= 40)

that meets the sides along sharp edges. Triangles about 1 mm across, faces outward, as binary
STL. Pure standard library; the output is the same on every run and platform.

    python3 examples/make_part.py [-o examples/domed_block.stl] [--cell 1.0]
"""
import argparse
import math
import os
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


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('-o', default=os.path.join(here, 'domed_block.stl'))
    ap.add_argument('--cell', type=float, default=1.0, help='triangle size, mm')
    a = ap.parse_args()
    tris = part(a.cell)
    write_stl(a.o, tris)
    print('%s: %d triangles' % (a.o, len(tris)))


if __name__ == '__main__':
    main()
