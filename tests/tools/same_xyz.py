#!/usr/bin/env python3
"""same_xyz.py IN.ply OUT.ply: exit 0 when every vertex of OUT has the x, y, z
bytes of IN's vertex in the same row (binary little-endian PLY, scalar vertex
properties), 1 with a message otherwise. Standard library only."""
import sys

SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2,
         "int16": 2, "uint16": 2, "int": 4, "uint": 4, "float": 4, "int32": 4,
         "uint32": 4, "float32": 4, "double": 8, "float64": 8}


def rows(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    n, offs, stride, in_vertex = 0, {}, 0, False
    for line in data[:end].decode("ascii").splitlines():
        t = line.split()
        if t[:1] == ["element"]:
            in_vertex = t[1] == "vertex"
            n = int(t[2]) if in_vertex else n
        elif t[:1] == ["property"] and in_vertex:
            offs[t[2]] = (stride, SIZES[t[1]], t[1])
            stride += SIZES[t[1]]
    return data[end:], n, offs, stride


a, na, oa, sa = rows(sys.argv[1])
b, nb, ob, sb = rows(sys.argv[2])
if na != nb:
    sys.exit(f"{na} vertices in, {nb} out")
for c in "xyz":
    if oa[c][2] != ob[c][2]:
        sys.exit(f"{c} is {oa[c][2]} in the input, {ob[c][2]} in the output")
for i in range(na):
    for c in "xyz":
        (pa, size, _), (pb, _, _) = oa[c], ob[c]
        if a[i * sa + pa:i * sa + pa + size] != b[i * sb + pb:i * sb + pb + size]:
            sys.exit(f"vertex {i}: {c} differs")
