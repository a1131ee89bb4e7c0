#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets into fuzz/corpus/<target>/ (small, valid and
near-valid files of every variant each reader knows, so the fuzzer starts past the headers).
Rerun after changing it; the files are committed."""
import json
import os
import struct
import sys

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
seeds = {}


def seed(target, name, data):
    seeds.setdefault(target, {})[name] = data.encode() if isinstance(data, str) else data


def lzf_literals(raw):
    """LZF stream of literal runs only (control byte = run length - 1, at most 32): valid LZF."""
    out = bytearray()
    for i in range(0, len(raw), 32):
        run = raw[i:i + 32]
        out.append(len(run) - 1)
        out += run
    return bytes(out)


pts = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.5), (0.0, 1.0, -0.25), (1.0, 1.0, 1e-3)]
nrm = [(0.0, 0.0, 1.0), (0.0, 0.6, 0.8), (0.6, 0.0, 0.8), (0.0, 0.0, -1.0)]

# ---- PLY ----
seed("ply", "ascii_normals.ply",
     "ply\nformat ascii 1.0\ncomment seed\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
     "property float nx\nproperty float ny\nproperty float nz\nend_header\n" +
     "".join("%g %g %g %g %g %g\n" % (p + n) for p, n in zip(pts, nrm)))
seed("ply", "ascii_faces.ply",
     "ply\r\nformat ascii 1.0\r\nobj_info seed\r\nelement vertex 3\r\nproperty double x\r\nproperty double y\r\n"
     "property double z\r\nproperty uchar red\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
     "end_header\r\n1 2 3 255\r\n4 5 6 0\r\n-7 8e-3 nan 7\r\n3 0 1 2\r\n\r\n")
head = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar confidence\nelement face 2\nproperty list uchar int vertex_indices\n"
        "end_header\n").encode()
body = b"".join(struct.pack("<fffB", *p, 9) for p in pts)
body += struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B3i", 3, 1, 3, 2)
seed("ply", "binary_le_faces.ply", head + body)
head = ("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
        "property double z\nproperty short nx\nproperty short ny\nproperty short nz\nelement range_grid 2\n"
        "property int index\nend_header\n").encode()
body = b"".join(struct.pack(">ddd3h", *p, *[int(v * 100) for v in n]) for p, n in zip(pts, nrm))
body += struct.pack(">2i", 0, -1)
seed("ply", "binary_be_normals.ply", head + body)
seed("ply", "empty_vertex.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty int8 x\nproperty uint16 y\n"
     "property float64 z\nend_header\n")

# ---- PCD ----
seed("pcd", "ascii.pcd",
     "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
     "WIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n" +
     "".join("%g %g %g\n" % p for p in pts))
seed("pcd", "ascii_normals_count.pcd",
     "VERSION .7\nFIELDS x y z rgb normal_x normal_y normal_z curvature hist\nSIZE 4 4 4 4 4 4 4 4 1\n"
     "TYPE F F F U F F F F I\nCOUNT 1 1 1 1 1 1 1 1 2\nWIDTH 2\nHEIGHT 2\nDATA ascii\n" +
     "".join("%g %g %g 4278190335 %g %g %g 0.01 -1 7\n" % (p + n) for p, n in zip(pts, nrm)))
head = ("VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 4\nHEIGHT 1\n"
        "POINTS 4\nDATA binary\n").encode()
seed("pcd", "binary.pcd", head + b"".join(struct.pack("<fffH", *p, 100) for p in pts))
head = ("VERSION 0.7\nFIELDS x y z _ normal_x normal_y normal_z\nSIZE 8 8 8 1 4 4 4\nTYPE F F F U F F F\n"
        "COUNT 1 1 1 3 1 1 1\nWIDTH 4\nHEIGHT 1\nPOINTS 4\nDATA binary_compressed\n").encode()
cols = [b"".join(struct.pack("<d", p[k]) for p in pts) for k in range(3)]
cols.append(b"\0" * 3 * 4)
cols += [b"".join(struct.pack("<f", n[k]) for n in nrm) for k in range(3)]
raw = b"".join(cols)
comp = lzf_literals(raw)
seed("pcd", "binary_compressed.pcd", head + struct.pack("<II", len(comp), len(raw)) + comp)
seed("pcd", "old_header.pcd",
     "COLUMNS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 2\nDATA ascii\n1 2 3\n4 5 6\n")

# ---- text columns (.xyz .csv .txt .pts) ----
seed("text", "blank.xyz", "".join("%g %g %g\n" % p for p in pts))
seed("text", "header_normals.csv",
     "x,y,z,nx,ny,nz\n" + "".join("%g, %g, %g,%g,%g,%g\n" % (p + n) for p, n in zip(pts, nrm)))
seed("text", "semicolons.txt", "# comment\r\n" + "".join("%g;%g;%g;7\r\n" % p for p in pts))
seed("text", "count_intensity.pts", "4\n" + "".join("%g %g %g -120 10 20 30\n" % p for p in pts))
seed("text", "bom_comments.xyz", "\xef\xbb\xbf1 2 3 # first\n\n4\t5\t6\n+7 -8e2 inf\n")

# ---- OFF ----
seed("off", "counts_inline.off", "OFF 4 2 0\n" + "".join("%g %g %g\n" % p for p in pts) + "3 0 1 2\n3 1 3 2\n")
seed("off", "noff.off", "NOFF\n# counts\n4 1\n" + "".join("%g %g %g %g %g %g\n" % (p + n) for p, n in zip(pts, nrm)) +
     "4 0 1 3 2\n")
seed("off", "coff_colours.off", "COFF\n3 1 3\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
     "3 0 1 2 0.5 0.5 0.5\n")

# ---- OBJ ----
seed("obj", "faces.obj", "# seed\no part\n" + "".join("v %g %g %g\n" % p for p in pts) +
     "vn 0 0 1\nvt 0.5 0.5\nf 1//1 2//1 3//1\nf 2 4 3\n")
seed("obj", "weights_colours.obj", "v 1 2 3 1.0\nv 4 5 6 0.1 0.2 0.3\r\nv -1e-3 +2 3e10\ng a\nusemtl m\nl 1 2\n")

# ---- STL ----
seed("stl", "ascii.stl", "solid seed\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
     "   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 1 0 0\n"
     "   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid seed\n")
tris = [(pts[0], pts[1], pts[2]), (pts[1], pts[3], pts[2])]
body = b"".join(struct.pack("<12fH", 0, 0, 1, *a, *b, *c, 0) for a, b, c in tris)
seed("stl", "binary.stl", b"binary seed".ljust(80, b" ") + struct.pack("<I", 2) + body)
seed("stl", "binary_says_solid.stl", b"solid but binary".ljust(80, b"\0") + struct.pack("<I", 2) + body)

# ---- graphs (text, then NUL-separated --set items) ----
graphs = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "graphs")
for name in sorted(os.listdir(graphs)):
    seed("graph", name, open(os.path.join(graphs, name), "rb").read())
prepare = json.load(open(os.path.join(graphs, "prepare-cloud.json")))
seed("graph", "prepare-sets.json",
     json.dumps(prepare).encode() + b"\0neighbours=16\0normals.orientation=\"up\"\0knn.k=[1]\0bad")
bad = {
    "scallop_graph": 1, "name": "bad",
    "params": {"r": {"value": "x", "unit": "mm"}, "k": 2.5},
    "inputs": {"cloud": {"type": "File", "default": "../escape.ply"}, "other": {"type": "Mesh"}},
    "nodes": [
        {"id": "a", "type": "cloud.knn", "params": {"k": "$k"}, "inputs": {"cloud": "b.cloud"}},
        {"id": "b", "type": "cloud.clean", "inputs": {"cloud": "a.neighbors"}},
        {"id": "c", "type": "cloud.kn", "params": {"k": 1e300}, "extra": 1},
        {"id": "a", "type": "post.gcode", "inputs": {"path": "@nowhere"}},
        7,
    ],
    "outputs": {"../x": "a.neighbors", "y": "zz", "z": "b.nothing"},
}
seed("graph", "bad.json", json.dumps(bad, indent=1))
seed("graph", "duplicates.json",
     '{"scallop_graph": 1, "scallop_graph": 2, "nodes": [{"id": "r", "type": "io.read_cloud", '
     '"inputs": {"file": "@c", "file": "@c"}, "params": {"scale": 2, "scale": 3}}], '
     '"inputs": {"c": {}}, "outputs": {"o": "r.cloud"}}')
seed("graph", "not_object.json", '[{"scallop_graph": 1}, "\\u00e9\\"", -0.0, 1e999]')

# The mesh reader target: the first byte picks the format (fuzz_read_mesh.cpp: 0 ply, 1 off,
# 2 obj, 3 stl), the rest is the file; the cloud targets' mesh files are its seeds too, plus
# faces with labels and feature edges.
for i, fmt in enumerate(("ply", "off", "obj", "stl")):
    for name, data in list(seeds.get(fmt, {}).items()):
        seed("mesh", "%s_%s" % (fmt, name), bytes([i]) + data)
seed("mesh", "ply_labels_features.ply", bytes([0]) + (
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
    "element face 2\nproperty list uchar uint vertex_indices\nproperty int label\n"
    "element edge 1\nproperty uint vertex1\nproperty uint vertex2\nproperty uchar feature\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 1\n3 0 1 2 5\n4 0 2 3 1 -1\n0 2 1\n").encode())

for target, files in seeds.items():
    d = os.path.join(root, target)
    os.makedirs(d, exist_ok=True)
    for name, data in files.items():
        with open(os.path.join(d, name), "wb") as f:
            f.write(data)
print("seeds written:", ", ".join("%s %d" % (t, len(f)) for t, f in seeds.items()), file=sys.stderr)
