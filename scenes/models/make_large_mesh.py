#!/usr/bin/env python3
"""Writes a large mesh for the BVH and cost-growth benchmarks: the Stanford bunny
(scenes/models/bunny.ply, 3674 triangles; see make_bunny_ply.mjs for its origin) with every
triangle cut into n x n smaller ones (n parts per edge), so 3674 n^2 triangles, as a binary
little-endian PLY. The surface is the bunny's: the new vertices lie in the original triangles'
planes, and a point on a shared edge is computed the same way from both sides (weights i/n on the
edge's two ends, in f64, rounded to f32 once), so the mesh has no cracks.

Not committed (tens of MB): generate it, then render scenes/perf/bunny_room_1m.json.

    python3 scenes/models/make_large_mesh.py                 # n = 17: 1,061,786 triangles
    python3 scenes/models/make_large_mesh.py --n 53 --out scenes/models/generated/bunny_10m.ply
"""
import argparse
import os
import struct
import sys
from array import array

HERE = os.path.dirname(os.path.abspath(__file__))


def read_bunny(path):
    """The vertices and triangles of make_bunny_ply.mjs's file (binary LE, float xyz, uchar/int)."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    nv = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
    nf = next(int(l.split()[2]) for l in header if l.startswith("element face"))
    xyz = struct.unpack_from("<%df" % (3 * nv), data, end)
    verts = [xyz[3 * i : 3 * i + 3] for i in range(nv)]
    faces = []
    off = end + 12 * nv
    for _ in range(nf):
        n, a, b, c = struct.unpack_from("<B3i", data, off)
        assert n == 3
        faces.append((a, b, c))
        off += 13
    return verts, faces


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=17, help="parts per edge (triangles x n^2)")
    ap.add_argument("--src", default=os.path.join(HERE, "bunny.ply"))
    ap.add_argument("--out", default=os.path.join(HERE, "generated", "bunny_1m.ply"))
    args = ap.parse_args()
    n = args.n
    verts, faces = read_bunny(args.src)

    # The grid of one triangle: vertex (i, j) has weights (n - i - j, i, j) / n on (a, b, c).
    grid = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]
    local = {ij: k for k, ij in enumerate(grid)}
    tris = []
    for i in range(n):
        for j in range(n - i):
            tris.append((local[(i, j)], local[(i + 1, j)], local[(i, j + 1)]))
            if i + j < n - 1:
                tris.append((local[(i + 1, j)], local[(i + 1, j + 1)], local[(i, j + 1)]))
    assert len(tris) == n * n

    out_v = array("f")
    out_f = bytearray()
    face = struct.Struct("<B3i")
    for t, (ia, ib, ic) in enumerate(faces):
        a, b, c = verts[ia], verts[ib], verts[ic]
        for i, j in grid:
            wa, wb, wc = (n - i - j) / n, i / n, j / n
            # An edge point has one weight 0; the sum of the other two is the same from both
            # triangles that share the edge.
            for k in range(3):
                terms = sorted(x for x in (wa * a[k], wb * b[k], wc * c[k]) if x != 0.0)
                out_v.append(sum(terms))
        base = t * len(grid)
        for p, q, r in tris:
            out_f += face.pack(3, base + p, base + q, base + r)
    nv = len(out_v) // 3
    nf = len(faces) * n * n
    if sys.byteorder != "little":
        out_v.byteswap()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"comment the Stanford bunny (npm bunny@1.0.1), each triangle cut in {n}x{n} by "
                "scenes/models/make_large_mesh.py\n"
                f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode("ascii")
        )
        out_v.tofile(f)
        f.write(out_f)
    print(f"wrote {args.out}: {nv} vertices, {nf} triangles")


if __name__ == "__main__":
    main()
