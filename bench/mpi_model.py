#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Cost model of pcl_dacpo_orient_mpi, fitted on a bench/mpi_scaling.sh run.

    bench/mpi_model.py WORK_DIR POINTS [--bandwidth GBps] [--block-points P]

WORK_DIR holds walls.txt and np<R>.json of mpi_scaling.sh for POINTS points.
The model (every constant measured in that run unless marked as assumed):

  T(n, R) = T01(n) + U(n) * imbalance / min(R, blocks) + C(n, R) + T5(blocks) + W(n)

  T01  rank 0 alone: read + k-NN + normals + blocks, scaled by n log n
  U    the block and edge units summed over ranks (one core each), linear in
       n at a fixed block size (the measured run's n / blocks points per
       block; the edges per block stay as measured); a rank runs whole
       blocks, ceil(blocks / R) of them
  imbalance  largest / mean busy time of the measured multi-rank runs;
       contention: summed busy time with one rank per core over one rank's
       (every core busy: shared memory bandwidth and clocks), assumed to hold
       on every node of a cluster
  C    every task and result passes rank 0's link: bytes per point (measured
       at the largest R, scaled by (R - 1) / R) / bandwidth (assumed, default
       10 GB/s: 100 Gb/s InfiniBand; here it is shared memory)
  T5   the 0-1 program and the finish: measured up to 200 blocks; beyond 2,000
       blocks the solver's 30 s time limit (bench_ilp: 4,000 blocks time out
       and the heuristic incumbent is the answer)
  W    rank 0 writes the output, linear in n
  memory: rank 0 holds the whole run (bytes per point measured), every other
       rank a fixed base plus its share n / R of the cloud (base and bytes per
       point from the two widest measured runs)
"""
import argparse
import json
import math
import os


def load(work):
    runs = {}
    with open(os.path.join(work, "walls.txt")) as f:
        for line in f:
            label, ranks, wall = line.split()
            rows = [json.loads(l) for l in open(os.path.join(work, label + ".json"))]
            runs[label] = {"ranks": int(ranks), "wall": float(wall), "rows": rows}
    return runs


def fit(runs, n, cores):
    np1 = runs["np1"]["rows"][0]
    multi = [r for k, r in runs.items() if k.startswith("np") and r["ranks"] > 1]
    imbalance = max(
        max(x["busy_s"] for x in r["rows"]) / (sum(x["busy_s"] for x in r["rows"]) / len(r["rows"]))
        for r in multi) if multi else 1.0
    # units run slower when every core of the machine works (memory bandwidth,
    # clocks): summed busy time of the run with one rank per core (the widest
    # run not oversubscribed, given as cores) over the one-rank run's
    fitting = [r for r in multi if r["ranks"] <= cores]
    contention = (max(sum(x["busy_s"] for x in r["rows"]) for r in fitting) / np1["busy_s"]
                  if fitting else 1.0)
    widest = max(multi, key=lambda r: r["ranks"]) if multi else runs["np1"]
    r0 = widest["rows"][0]
    R = widest["ranks"]
    hub_bytes = (r0["sent_mb"] + r0["received_mb"]) * 1048576.0 / ((R - 1) / R) if R > 1 else 0.0
    # other ranks: a fixed base (the MPI runtime, the program) plus their
    # share of the cloud; base and slope from the two widest runs
    shares = sorted((r["ranks"], max(x["peak_rss_mb"] for x in r["rows"][1:])) for r in multi)
    if len(shares) >= 2:
        (ra, ma), (rb, mb) = shares[0], shares[-1]
        slope = (ma - mb) / (n / ra - n / rb) if ra != rb else 0.0
        base = mb - slope * n / rb
    else:
        slope, base = 0.0, (shares[0][1] if shares else 0.0)
    return {
        "n": n,
        "blocks": np1["blocks"],
        "t01_per_nlogn": np1["read_stages01_s"] / (n * math.log(n)),
        "unit_s_per_point": np1["busy_s"] / n,
        "imbalance": imbalance,
        "contention": contention,
        "hub_bytes_per_point": hub_bytes / n,
        "t5_measured": np1["solve_s"],
        "write_per_point": np1["write_s"] / n,
        "rank0_mb_per_point": r0["peak_rss_mb"] / n,
        "other_mb_per_point_share": slope,
        "other_base_mb": base,
    }


def predict(m, n, R, bandwidth_gbps, block_points):
    blocks = max(1, round(n / block_points))
    t01 = m["t01_per_nlogn"] * n * math.log(n)
    # a rank runs whole blocks: ceil(blocks / R) of them at the mean cost
    per_block = m["unit_s_per_point"] * n / blocks
    units = per_block * math.ceil(blocks / R) * (
        m["imbalance"] * m["contention"] if R > 1 else 1.0)
    comm = m["hub_bytes_per_point"] * n * ((R - 1) / R) / (bandwidth_gbps * 1e9) if R > 1 else 0.0
    t5 = m["t5_measured"] * n / m["n"] if blocks <= 2000 else 30.0 + m["t5_measured"] * n / m["n"]
    write = m["write_per_point"] * n
    return {
        "blocks": blocks,
        "t01": t01,
        "units": units,
        "comm": comm,
        "t5": t5,
        "write": write,
        "total": t01 + units + comm + t5 + write,
        "rank0_gb": m["rank0_mb_per_point"] * n / 1024.0,
        "other_gb": (m["other_base_mb"] + m["other_mb_per_point_share"] * n / R) / 1024.0
        if R > 1 else 0.0,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("work")
    ap.add_argument("points", type=int)
    ap.add_argument("--bandwidth", type=float, default=10.0, help="GB/s at rank 0 (assumed)")
    ap.add_argument("--cores", type=int, default=os.cpu_count(),
                    help="cores of the measuring machine (runs with more ranks are oversubscribed)")
    ap.add_argument("--block-points", type=float, default=0.0,
                    help="points per block (default: as measured)")
    a = ap.parse_args()
    runs = load(a.work)
    m = fit(runs, a.points, a.cores)
    bp = a.block_points or a.points / m["blocks"]
    print("fitted on %d points, %d blocks (%.0f points per block)" % (a.points, m["blocks"], bp))
    print("  rank 0 read + stages 0-1: %.3g s per n log n" % m["t01_per_nlogn"])
    print("  units (blocks + edges), one core: %.3g s per point" % m["unit_s_per_point"])
    print("  load imbalance (largest / mean busy): %.2f" % m["imbalance"])
    print("  units slower with every core busy: x %.2f" % m["contention"])
    print("  through rank 0's link: %.0f bytes per point" % m["hub_bytes_per_point"])
    print("  rank 0 peak: %.0f bytes per point; other ranks: %.0f MB + %.0f bytes per point of "
          "their share" % (m["rank0_mb_per_point"] * 1048576, m["other_base_mb"],
                           m["other_mb_per_point_share"] * 1048576))
    print()
    print("| points | ranks | blocks | rank 0 stages 0-1 s | units s | comm s | solve s | write s "
          "| total s | measured s (%d cores) | rank 0 GB | other ranks GB |" % a.cores)
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, R in [(a.points, r["ranks"]) for k, r in sorted(runs.items()) if k.startswith("np")] + \
            [(a.points, 64), (a.points, 1024), (10**9, 64), (10**9, 1024)]:
        p = predict(m, n, R, a.bandwidth, bp)
        measured = runs.get("np%d" % R, {}).get("wall") if n == a.points else None
        print("| %.0e | %d | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %s | %.1f | %.2f |" % (
            n, R, p["blocks"], p["t01"], p["units"], p["comm"], p["t5"], p["write"], p["total"],
            "%.1f" % measured if measured else "—", p["rank0_gb"], p["other_gb"]))


if __name__ == "__main__":
    main()
