#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Peer method for the pcl_dacpo benchmark: Open3D's normal orientation.

    open3d_orient.py in.ply out.ply [-normal_k 16] [-k 10] [-threads N]

Reads the points (any normals in the file are ignored), estimates PCA normals
with Open3D's estimate_normals(KDTreeSearchParamKNN(normal_k)) and orients them
with orient_normals_consistent_tangent_plane(k) (Hoppe et al. 1992: minimum
spanning tree over a Riemannian graph). Writes binary PLY float x y z nx ny nz
in input order, readable by pcl_dacpo_eval. The last stderr line is
"stats: points=N seconds=S" (S = estimate + orient, without file I/O).
Needs the Debian package python3-open3d (run with /usr/bin/python3)."""
import os
import sys
import time


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    src, dst = argv[1], argv[2]
    normal_k, k, threads = 16, 10, 0
    i = 3
    while i < len(argv):
        if argv[i] == "-normal_k":
            normal_k = int(argv[i + 1]); i += 2
        elif argv[i] == "-k":
            k = int(argv[i + 1]); i += 2
        elif argv[i] == "-threads":
            threads = int(argv[i + 1]); i += 2
        else:
            print(f"open3d_orient: unknown option {argv[i]}", file=sys.stderr)
            return 2
    if threads > 0:  # Open3D uses OpenMP; must be set before the import
        os.environ["OMP_NUM_THREADS"] = str(threads)
    import numpy as np
    import open3d as o3d

    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    pcd = o3d.io.read_point_cloud(src)  # keeps NaN points, so the order is kept
    n = len(pcd.points)
    if n == 0:
        print(f"open3d_orient: no points read from {src}", file=sys.stderr)
        return 1
    pcd.normals = o3d.utility.Vector3dVector()  # orient from unsigned PCA axes only
    t0 = time.perf_counter()
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=normal_k))
    pcd.orient_normals_consistent_tangent_plane(k)
    secs = time.perf_counter() - t0

    xyz = np.asarray(pcd.points, dtype=np.float32)
    nrm = np.asarray(pcd.normals, dtype=np.float32)
    if nrm.shape != xyz.shape:
        print("open3d_orient: Open3D returned no normals", file=sys.stderr)
        return 1
    data = np.hstack([xyz, nrm]).astype("<f4")
    header = ("ply\nformat binary_little_endian 1.0\n"
              "comment normals: Open3D estimate_normals(knn=%d) + "
              "orient_normals_consistent_tangent_plane(%d)\n"
              "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\nend_header\n"
              % (normal_k, k, n))
    with open(dst, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(data.tobytes())
    print(f"stats: points={n} seconds={secs:.3f} open3d={o3d.__version__}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
