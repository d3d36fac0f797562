#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Subsampled variants of scans with ground-truth normals, as users thin them.

For every binary little-endian PLY of the inputs whose vertices are exactly
`float x y z nx ny nz`, writes to OUT:
  NAME_v1.ply, NAME_v2.ply, NAME_v4.ply  one point per 1 / 2 / 4 cm voxel (the
                                         point nearest the voxel's centre, so
                                         its ground truth stays exact)
  NAME_r30k.ply                          30,000 points drawn at random (seed 1;
                                         only for clouds larger than that)
Points keep their input order. Then measure them, e.g.
  bench/robustness.py --label sub --seeds 1,2,3 OUT
Needs numpy.
"""
import argparse
import os
import sys

import numpy as np

FIELDS = ("x", "y", "z", "nx", "ny", "nz")


def read_ply(path):
    with open(path, "rb") as fh:
        header = []
        while True:
            line = fh.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            line = line.decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        props = [h.split()[-1] for h in header if h.startswith("property")]
        count = [int(h.split()[-1]) for h in header if h.startswith("element vertex")]
        if ("format binary_little_endian 1.0" not in header or tuple(props) != FIELDS or
                any(h.startswith("property") and h.split()[1] != "float" for h in header) or
                len(count) != 1):
            raise ValueError(f"{path}: not binary little-endian float x y z nx ny nz")
        data = np.frombuffer(fh.read(24 * count[0]), dtype="<f4")
    if data.size != 6 * count[0]:
        raise ValueError(f"{path}: truncated")
    return data.reshape(-1, 6)


def write_ply(path, rows):
    with open(path, "wb") as fh:
        fh.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(rows)}\n".encode())
        for f in FIELDS:
            fh.write(f"property float {f}\n".encode())
        fh.write(b"end_header\n")
        fh.write(np.ascontiguousarray(rows, dtype="<f4").tobytes())


def voxel_pick(xyz, size):
    """Indices (in input order) of the point nearest each occupied voxel's centre."""
    key = np.floor(xyz / size).astype(np.int64)
    d2 = ((xyz - (key + 0.5) * size) ** 2).sum(1)
    order = np.lexsort((d2, key[:, 2], key[:, 1], key[:, 0]))
    k = key[order]
    first = np.r_[True, (np.diff(k, axis=0) != 0).any(1)]
    return np.sort(order[first])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="+", help="PLY files or folders of them")
    ap.add_argument("-o", dest="out", required=True, help="output folder (created)")
    opt = ap.parse_args()
    files = []
    for p in opt.inputs:
        files += sorted(os.path.join(p, f) for f in os.listdir(p) if f.endswith(".ply")) \
            if os.path.isdir(p) else [p]
    os.makedirs(opt.out, exist_ok=True)
    for f in files:
        try:
            rows = read_ply(f)
        except (OSError, ValueError) as e:
            print(f"skipped: {e}", file=sys.stderr)
            continue
        name = os.path.splitext(os.path.basename(f))[0]
        xyz = rows[:, :3].astype(np.float64)
        for cm in (1, 2, 4):
            write_ply(os.path.join(opt.out, f"{name}_v{cm}.ply"), rows[voxel_pick(xyz, cm / 100.0)])
        if len(rows) > 30000:
            pick = np.sort(np.random.default_rng(1).choice(len(rows), 30000, replace=False))
            write_ply(os.path.join(opt.out, f"{name}_r30k.ply"), rows[pick])
        print(f"{name}: {len(rows)} points")


if __name__ == "__main__":
    main()
