#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Robustness suite: every ground-truth PLY of the given folders, oriented by
pcl_dacpo with several seeds, scored by pcl_dacpo_eval, split by where the
error comes from.

Per file: the median and the worst error over the seeds, their spread
(max - min), and for the median run the split into
  in-block  = wrong with the best sign per block (stages 0-3),
  flip      = wrong with the best sign per component minus in-block (stage 4-5),
  component = wrong overall minus wrong with the best sign per component
              (relative sign of disconnected parts).
Every run is cached in <work>/runs/<label>/<file>.s<seed>.json, so a second
call with the same label only reports; --force runs again.

usage: bench/robustness.py [-b BUILD] [-w WORK] [--label L] [--seeds 1,2,3,4,5]
                           [--jobs 2] [--force] [--json OUT] [--md OUT]
                           [--args "-c 2 ..."] DIR_OR_PLY [DIR_OR_PLY ...]
"""
import argparse, glob, json, os, statistics, subprocess, sys, time
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="+", help="folders of *.ply with ground-truth normals, or files")
    ap.add_argument("-b", dest="build", default=os.path.join(ROOT, "build"))
    ap.add_argument("-w", dest="work", default=None, help="default: <build>/robustness")
    ap.add_argument("--label", default="default", help="name of this configuration")
    ap.add_argument("--args", default="", help="extra pcl_dacpo_orient arguments")
    ap.add_argument("--block-factor", type=float, default=None,
                    help="run with -blocks = factor x the automatic count (n/625 in [1, 400]): "
                         "sensitivity to the block count")
    ap.add_argument("--peer", default=None,
                    help="score a peer program instead (called as PEER in.ply out.ply ARGS, "
                         "e.g. the benchmark's cgal_orient); no error split, seeds ignored")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--jobs", type=int, default=2, help="runs at once, one thread each")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--json", default=None, help="write the per-file summary as JSON")
    ap.add_argument("--md", default=None, help="write the table as Markdown")
    return ap.parse_args()


def files_of(inputs):
    out = []
    for p in inputs:
        if os.path.isdir(p):
            out += sorted(glob.glob(os.path.join(p, "*.ply")))
        elif os.path.isfile(p):
            out.append(p)
        else:
            print(f"robustness: skipping {p} (not found)", file=sys.stderr)
    return out


def ply_vertices(path):
    with open(path, "rb") as fh:
        for _ in range(200):
            line = fh.readline().decode("ascii", "replace").strip()
            if line.startswith("element vertex"):
                return int(line.split()[-1])
            if line == "end_header":
                break
    return 0


def run_one(opt, f, seed):
    name = os.path.splitext(os.path.basename(f))[0]
    d = os.path.join(opt.work, "runs", opt.label)
    os.makedirs(d, exist_ok=True)
    rec_path = os.path.join(d, f"{name}.s{seed}.json")
    if not opt.force and os.path.exists(rec_path):
        with open(rec_path) as fh:
            return json.load(fh)
    tools = os.path.join(opt.build, "wrappers")
    if opt.peer:
        pred = os.path.join(d, f"{name}.s{seed}.ply")
        cmd = [opt.peer, f, pred] + opt.args.split()
    else:
        pred = os.path.join(d, f"{name}.s{seed}.pcd")
        cmd = [os.path.join(tools, "pcl_dacpo_orient"), f, pred, "-estimate", "-labels",
               "-seed", str(seed), "-threads", "1"] + opt.args.split()
        if opt.block_factor:
            auto = min(400, max(1, ply_vertices(f) // 625))
            cmd += ["-blocks", str(max(1, round(auto * opt.block_factor)))]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    rec = dict(file=name, seed=seed, label=opt.label, args=opt.args, wall_s=wall, rc=r.returncode)
    if r.returncode != 0:
        rec["error"] = (r.stdout + r.stderr)[-2000:]
    else:
        e = subprocess.run([os.path.join(tools, "pcl_dacpo_eval"), f, pred, "-json"],
                           stdin=subprocess.DEVNULL, capture_output=True, text=True)
        try:
            ev = json.loads(e.stdout.strip().splitlines()[-1])
        except (ValueError, IndexError):
            ev = None
        if ev is None:
            rec["error"] = (e.stdout + e.stderr)[-2000:]
        else:
            rec.update(points=ev["points"], wrong=ev["wrong_pct"],
                       comp_best=ev.get("component_wrong_pct", ev["wrong_pct"]),
                       in_block=ev.get("intra_block_wrong_pct", ev["wrong_pct"]),
                       blocks=ev.get("blocks", 0), components=ev["components"])
            if "right_sign_pct" in ev:
                rec["right_sign"] = ev["right_sign_pct"]
            if "wrong_in_least_confident10_pct" in ev:
                rec["wrong_in_low_conf10"] = ev["wrong_in_least_confident10_pct"]
            rec["flip"] = rec["comp_best"] - rec["in_block"]
            rec["component"] = rec["wrong"] - rec["comp_best"]
        os.remove(pred)
    with open(rec_path, "w") as fh:
        json.dump(rec, fh)
    return rec


def summarize(recs):
    ok = [r for r in recs if "wrong" in r]
    if not ok:
        return None
    ok.sort(key=lambda r: r["wrong"])
    med = ok[(len(ok) - 1) // 2]  # lower median: a run that happened
    return dict(file=ok[0]["file"], points=ok[0]["points"], runs=len(ok), failed=len(recs) - len(ok),
                median=statistics.median(r["wrong"] for r in ok), worst=ok[-1]["wrong"],
                best=ok[0]["wrong"], spread=ok[-1]["wrong"] - ok[0]["wrong"],
                in_block=med["in_block"], flip=med["flip"], component=med["component"],
                wall_s=statistics.median(r["wall_s"] for r in ok),
                low_conf10=(statistics.median(r["wrong_in_low_conf10"] for r in ok)
                            if all("wrong_in_low_conf10" in r for r in ok) else None),
                right_sign=(sum(r["right_sign"] > 50.0 for r in ok)
                            if all("right_sign" in r for r in ok) else None),
                per_seed={str(r["seed"]): round(r["wrong"], 3) for r in ok})


def table(label, groups):
    lines = [f"### {label}", "",
             "| file | points | median % | worst % | spread | in-block | flip | component | right sign | s/run |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    sign = lambda s: "—" if s["right_sign"] is None else f"{s['right_sign']}/{s['runs']}"
    for gname, rows in groups:
        for s in rows:
            lines.append(f"| {s['file']} | {s['points']} | {s['median']:.2f} | {s['worst']:.2f} | "
                         f"{s['spread']:.2f} | {s['in_block']:.2f} | {s['flip']:.2f} | "
                         f"{s['component']:.2f} | {sign(s)} | {s['wall_s']:.1f} |")
        if rows:
            m = lambda k: sum(r[k] for r in rows) / len(rows)
            signs = [r for r in rows if r["right_sign"] is not None]
            total_sign = (f"{sum(r['right_sign'] for r in signs)}/{sum(r['runs'] for r in signs)}"
                          if signs else "—")
            lines.append(f"| **mean {gname}** ({len(rows)}) | | **{m('median'):.2f}** | {m('worst'):.2f} | "
                         f"max {max(r['spread'] for r in rows):.2f} | {m('in_block'):.2f} | "
                         f"{m('flip'):.2f} | {m('component'):.2f} | {total_sign} | {m('wall_s'):.1f} |")
    return "\n".join(lines)


def main():
    opt = parse()
    opt.work = opt.work or os.path.join(opt.build, "robustness")
    seeds = [int(s) for s in opt.seeds.split(",") if s]
    if opt.peer:
        seeds = seeds[:1]
    groups = []
    for inp in opt.inputs:
        fs = files_of([inp])
        jobs = [(f, s) for f in fs for s in seeds]
        with ThreadPoolExecutor(max_workers=max(1, opt.jobs)) as ex:
            recs = list(ex.map(lambda a: run_one(opt, *a), jobs))
        rows = []
        for f in fs:
            name = os.path.splitext(os.path.basename(f))[0]
            s = summarize([r for r in recs if r["file"] == name])
            if s:
                rows.append(s)
            for r in recs:
                if r["file"] == name and "error" in r:
                    print(f"robustness: {name} seed {r['seed']} failed: {r['error'][-300:]}", file=sys.stderr)
        groups.append((os.path.basename(os.path.normpath(inp)), rows))
    what = (os.path.basename(opt.peer) + " " + opt.args) if opt.peer else \
        f"pcl_dacpo_orient -estimate {opt.args}, seeds {opt.seeds}"
    md = table(f"{opt.label} ({what.strip()})", groups)
    print(md)
    if opt.md:
        with open(opt.md, "w") as fh:
            fh.write(md + "\n")
    if opt.json:
        with open(opt.json, "w") as fh:
            json.dump(dict(label=opt.label, args=opt.args, seeds=seeds,
                           groups={g: rows for g, rows in groups}), fh, indent=1)


if __name__ == "__main__":
    main()
