#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Cost model of pcl_dacpo_orient_mpi -memory (tiles), fitted on a
bench/tiles_scaling.sh run, and its prediction for larger scans and clusters.

    bench/tiles_model.py WORK_DIR POINTS [--cores C] [--net GBps] [--disk GBps]
                         [--predict N] [--memory BYTES]

WORK_DIR holds np<R>.json of tiles_scaling.sh for POINTS points. Model (every
constant measured in that run unless marked as assumed):

  T(n, R) = T_read + T_route + T_tiles + T_join + T_write

  T_read   every rank reads its n / R points twice (sample pass, route pass)
           and once more to write: seconds per point of the one-rank run
  T_route  each point (and its halo copies, share h measured) travels once,
           24 bytes; per-rank time per point measured on one rank, plus the
           traffic over an assumed per-node network bandwidth (--net, 10 GB/s)
  T_tiles  tiles are the unit: a rank runs ceil(T / R) tiles of about
           max_points(1 + h) / (1 + h) points; seconds per point of a tile's
           dacpo_orient() measured (busy / held points, one rank), times the
           contention of every core busy (summed busy of the widest run that
           does not oversubscribe over the one-rank run's)
  T_join   halo normals (32 bytes each) to their owners; the evidence of the
           tile pairs (24 bytes each, about 26 neighbours per tile, assumed:
           a cell of a 3-D kd-split) gathered on rank 0; a spanning tree
           (negligible)
  T_write  every own normal (24 bytes) to its range's rank, then each rank
           writes n / R x 24 bytes; an assumed aggregate file-system bandwidth
           (--disk, 10 GB/s shared by all ranks) bounds it
  measured machine: R ranks share --cores cores (more ranks than cores run
           their tiles in turn); a cluster: one core per rank
  memory per rank: its tiles' points (16 bytes each; held = n (1 + h) / R),
           one tile's dacpo_orient() (measured, scaled with the tile's
           points), its range's normals (12 bytes a point) and, on rank 0,
           the pair evidence

The tile count follows from the budget (dacpo_tiled_points_for_memory:
(bytes - 96 MiB) / 800 points of own + halo, cut at 0.8 of that), not from R:
that is why the answer is the same for any number of ranks.
"""
import argparse
import json
import math
import os

BYTES_PER_POINT = 800.0
BASE = 96 * 1024 * 1024


def tile_points(memory):
    return max(16, int((memory - BASE) / BYTES_PER_POINT))


def load(work):
    runs = {}
    for name in os.listdir(work):
        if name.startswith("np") and name.endswith(".json"):
            rows = [json.loads(l) for l in open(os.path.join(work, name))]
            runs[len(rows)] = rows
    return runs


def fit(runs, n, cores):
    one = runs[1][0]
    held = one["held_points"]
    fitting = [r for R, r in runs.items() if 1 < R <= cores]
    contention = (max(sum(x["busy_s"] for x in r) for r in fitting) / one["busy_s"]
                  if fitting else 1.0)
    return {
        "halo_share": held / n - 1.0,
        "tiles": one["num_tiles"],
        "read_s_per_point": (one["read_plan_s"] + one["write_s"]) / n,
        "route_s_per_point": one["route_s"] / n,
        "tile_s_per_point": one["busy_s"] / held,
        "contention": contention,
        # a rank's peak beyond its tiles' points (16 bytes) and its range's
        # normals (12 bytes): one tile's dacpo_orient() and the process
        "tile_run_mb": sum(x["peak_rss_mb"] - 16e-6 * x["held_points"] - 12e-6 * n / len(r)
                           for r in runs.values() for x in r) / sum(len(r) for r in runs.values()),
        "tile_points": held / one["num_tiles"],
    }


def predict(m, n, R, memory, net, disk, cores=None):
    h = m["halo_share"]
    tp = tile_points(memory)
    # median cuts halve a cell until it holds at most 0.8 tp own points
    T = 2 ** max(0, math.ceil(math.log2(n / (0.8 * tp))))
    per_tile = n * (1 + h) / T
    P = min(R, cores) if cores else R  # ranks that compute at once
    t_read = m["read_s_per_point"] * n / R
    t_route = m["route_s_per_point"] * n / R + 24.0 * n * (1 + h) / R / (net * 1e9)
    t_tiles = (math.ceil(T / R) * R / P) * per_tile * m["tile_s_per_point"] * \
        (m["contention"] if R > 1 else 1.0)
    t_join = 32.0 * n * h / R / (net * 1e9) + 24.0 * 26 * T / (net * 1e9)
    t_write = 24.0 * n / R / (net * 1e9) + 24.0 * n / (disk * 1e9)
    # one tile's run scales with its points (assumed proportional)
    mem = (16.0 * n * (1 + h) / R + 12.0 * n / R) / 1e9 + \
        m["tile_run_mb"] / 1e3 * per_tile / m["tile_points"]
    mem0 = mem + 24.0 * 26 * T / 1e9
    return T, t_read, t_route, t_tiles, t_join, t_write, mem, mem0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("work")
    ap.add_argument("points", type=float)
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--net", type=float, default=10.0, help="GB/s per node (assumed)")
    ap.add_argument("--disk", type=float, default=10.0, help="GB/s of the file system (assumed)")
    ap.add_argument("--memory", type=float, default=1024 ** 3, help="-memory of the measured run")
    ap.add_argument("--predict", type=float, default=1e9)
    o = ap.parse_args()
    runs = load(o.work)
    m = fit(runs, o.points, o.cores)
    print("fitted on %.3g points, %d tiles, -memory %.3g bytes" % (o.points, m["tiles"], o.memory))
    for k in ("halo_share", "read_s_per_point", "route_s_per_point", "tile_s_per_point",
              "contention", "tile_run_mb", "tile_points"):
        print("  %s: %.4g" % (k, m[k]))
    print()
    print("| points | ranks | -memory | tiles | read s | route s | tiles s | join s | write s "
          "| total s | measured s | GB per rank (rank 0) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, R, mem in ([(o.points, R, o.memory) for R in sorted(runs)] +
                      [(o.predict, R, mem) for R in (64, 1024) for mem in (o.memory, 4 * 1024 ** 3)]):
        T, a, b, c, d, e, g, g0 = predict(m, n, R, mem, o.net, o.disk,
                                          o.cores if n == o.points else None)
        measured = "—"
        if n == o.points and R in runs:
            measured = "%.1f" % max(sum(x[k] for k in ("read_plan_s", "route_s", "tiles_s", "join_s",
                                                       "write_s")) for x in runs[R])
        print("| %.0e | %d | %.0fG | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %s | %.2f (%.2f) |"
              % (n, R, mem / 1024 ** 3, T, a, b, c, d, e, a + b + c + d + e, measured, g, g0))


if __name__ == "__main__":
    main()
