#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The README's results from today's code, in one command (bench/report.sh).

  1. accuracy: every suite (a folder of PLYs with ground-truth normals) oriented
     by pcl_dacpo with seeds 1-5 and once by each peer (CGAL's MST, Open3D's
     tangent-plane MST, PCL's flip towards the centroid), all from unsigned PCA
     normals (k = 16), scored by pcl_dacpo_eval (bench/robustness.py runs them);
  2. time and peak memory against points: generated rooms of growing size,
     every method once, end to end (read, orient, write) under /usr/bin/time;
  3. plots (matplotlib): error per suite and method, time and memory against
     points; pictures: bench/render.sh (errors in red, and the signs as
     returned);
  4. bench/results/report.md (tables, date, machine, commit), printed, and the
     README's block between its two "bench/report.sh" markers replaced by it.

usage: bench/report.sh [--suite NAME=DIR ...] [--seeds 1,2,3,4,5]
                       [--sizes 50000,100000,200000,500000] [--no-render]
                       [--no-readme] [-b BUILD] [-w WORK] [-o RESULTS]
Suites: --suite, else $DACPO_SUITES ("name=dir:name=dir"), else four rooms
made by dacpo_make_scene (the command then works on any clone).
"""
import argparse, hashlib, json, os, platform, re, subprocess, sys, time
from datetime import datetime, timezone

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
METHODS = [  # key, label, peer program (None: pcl_dacpo)
    ("dacpo", "pcl_dacpo", None),
    ("cgal", "CGAL mst_orient_normals (k=10)", "cgal_orient"),
    ("open3d", "Open3D tangent-plane MST (k=10)", "open3d_orient.py"),
    ("pcl_viewpoint", "PCL flip towards the centroid", "pcl_viewpoint"),
]
BEGIN, END = "<!-- bench/report.sh: begin -->", "<!-- bench/report.sh: end -->"


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run(cmd, **kw):
    return subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True, **kw)


def parse():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--suite", action="append", default=[], help="NAME=DIR (repeatable)")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--sizes", default="50000,100000,200000,500000")
    ap.add_argument("--time-limit", type=float, default=120.0,
                    help="seconds per scaling run; a method that takes longer is not run on "
                         "larger rooms (Open3D's MST is far superlinear on exactly planar rooms)")
    ap.add_argument("--no-render", action="store_true", help="keep the pictures as they are")
    ap.add_argument("--no-readme", action="store_true", help="write report.md only")
    ap.add_argument("--rewrite", action="store_true",
                    help="run nothing: report.md and the README block again from report.json")
    ap.add_argument("-b", dest="build", default=os.path.join(ROOT, "build"))
    ap.add_argument("-w", dest="work", default=None, help="default: <build>/report")
    ap.add_argument("-o", dest="results", default=os.path.join(ROOT, "bench", "results"))
    opt = ap.parse_args()
    opt.work = opt.work or os.path.join(opt.build, "report")
    opt.tools = os.path.join(opt.build, "wrappers")
    return opt


def tools_and_peers(opt):
    """Builds what is missing; returns {method key: peer command or None}."""
    need = ("dacpo_make_scene", "pcl_dacpo_orient", "pcl_dacpo_eval")
    if not all(os.access(os.path.join(opt.tools, t), os.X_OK) for t in need):
        log(f"# building pcl_dacpo in {opt.build}")
        if run(["cmake", "-S", ROOT, "-B", opt.build, "-DCMAKE_BUILD_TYPE=Release"]).returncode or \
                run(["cmake", "--build", opt.build, "-j", str(os.cpu_count() or 2)]).returncode:
            sys.exit("report: the tools do not build (scripts/install_deps.sh installs what they need)")
    peers_build = os.path.join(opt.work, "peers-build")
    r = run(["cmake", "-S", os.path.join(ROOT, "bench", "peers"), "-B", peers_build,
             "-DCMAKE_BUILD_TYPE=Release"])
    if r.returncode == 0:
        r = run(["cmake", "--build", peers_build, "-j", str(os.cpu_count() or 2)])
    found = {"dacpo": None}
    for key, _, prog in METHODS[1:]:
        path = os.path.join(ROOT, "bench", "peers", prog) if prog.endswith(".py") else \
            os.path.join(peers_build, prog)
        ok = os.access(path, os.X_OK)
        if ok and prog.endswith(".py"):
            ok = run(["/usr/bin/python3", "-c", "import open3d"]).returncode == 0
        if ok:
            found[key] = path
        else:
            log(f"report: peer {prog} not available (scripts/install_bench_deps.sh); its column stays empty")
    return found


def suites(opt):
    pairs = opt.suite or [s for s in os.environ.get("DACPO_SUITES", "").split(":") if s]
    out = []
    for p in pairs:
        name, _, d = p.rpartition("=")
        d = os.path.abspath(d)
        if not os.path.isdir(d):
            sys.exit(f"report: suite folder {d} not found")
        out.append((name or os.path.basename(d), d))
    if out:
        return out
    d = os.path.join(opt.work, "generated")
    os.makedirs(d, exist_ok=True)
    for name, args in (("room_clean", []), ("room_noise004", ["-noise", "0.004"]),
                       ("room_noise008", ["-noise", "0.008"]), ("room_10k", ["-downsample", "10000"])):
        f = os.path.join(d, name + ".ply")
        if not os.path.exists(f):
            run([os.path.join(opt.tools, "dacpo_make_scene"), f, "-scene", "room", "-n", "100000",
                 "-seed", "1"] + args)
    return [("generated", d)]


def label_of(key, prog):
    """Cache label: pcl_dacpo per commit (and uncommitted change), a peer per its source."""
    h = hashlib.sha1()
    if prog is None:
        h.update(run(["git", "-C", ROOT, "rev-parse", "HEAD"]).stdout.encode())
        h.update(run(["git", "-C", ROOT, "diff", "HEAD", "--", "c_core", "wrappers"]).stdout.encode())
    else:
        for f in sorted(os.listdir(os.path.join(ROOT, "bench", "peers"))):
            h.update(open(os.path.join(ROOT, "bench", "peers", f), "rb").read())
    return f"report-{key}-{h.hexdigest()[:10]}"


def accuracy(opt, found, suite_list):
    """{suite: {method: robustness.py summary rows}}"""
    res = {}
    for sname, d in suite_list:
        res[sname] = {}
        for key, _, prog in METHODS:
            if key not in found:
                continue
            out = os.path.join(opt.work, f"acc_{sname}_{key}.json")
            cmd = [sys.executable, os.path.join(ROOT, "bench", "robustness.py"), "-b", opt.build,
                   "-w", os.path.join(opt.work, "robustness"), "--label", label_of(key, prog),
                   "--seeds", opt.seeds, "--json", out, d]
            if found[key]:
                cmd += ["--peer", found[key]]
            log(f"# accuracy: {sname} / {key}")
            t0 = time.time()
            r = run(cmd)
            if r.returncode != 0:
                log(r.stderr[-2000:])
                sys.exit(f"report: robustness.py failed on {sname} / {key}")
            res[sname][key] = next(iter(json.load(open(out))["groups"].values()))
            log(f"#   {time.time() - t0:.0f} s")
    return res


def timed(cmd, limit):
    """(wall s, peak RSS MB, rc) of one run under /usr/bin/time; rc 124 past limit."""
    r = run(["/usr/bin/time", "-f", "TIME %e %M", "timeout", str(limit)] + cmd)
    m = re.findall(r"TIME ([0-9.]+) ([0-9]+)", r.stderr)
    if not m:
        return None, None, r.returncode or 1
    return float(m[-1][0]), int(m[-1][1]) / 1024.0, r.returncode


def scaling(opt, found):
    """[{points, method: {wall, rss, wrong}}] on generated rooms of growing size."""
    rows, over = [], set()
    d = os.path.join(opt.work, "scaling")
    os.makedirs(d, exist_ok=True)
    for n in [int(s) for s in opt.sizes.split(",") if s]:
        room = os.path.join(d, f"room_{n}.ply")
        if not os.path.exists(room):
            run([os.path.join(opt.tools, "dacpo_make_scene"), room, "-scene", "room", "-n", str(n),
                 "-seed", "1"])
        row = {"points": n}
        for key, _, prog in METHODS:
            if key not in found:
                continue
            if key in over:
                row[key] = dict(wall=None, rss=None, wrong=None, rc=124, skipped=True)
                continue
            pred = os.path.join(d, f"pred_{key}.ply")
            cmd = [found[key], room, pred] if found[key] else \
                [os.path.join(opt.tools, "pcl_dacpo_orient"), room, pred, "-estimate", "-q"]
            wall, rss, rc = timed(cmd, opt.time_limit)
            if rc == 124:
                over.add(key)
            wrong = None
            if rc == 0:
                ev = run([os.path.join(opt.tools, "pcl_dacpo_eval"), room, pred, "-json"])
                wrong = json.loads(ev.stdout.strip().splitlines()[-1])["wrong_pct"]
            row[key] = dict(wall=wall, rss=rss, wrong=wrong, rc=rc)
            log(f"# scaling {n} {key}: {wall} s, {rss and round(rss)} MB, {wrong} % wrong")
        rows.append(row)
    return rows


def suite_cell(rows):
    """(mean of the per-file medians, mean of the worst seeds, files)."""
    if not rows:
        return None
    return (sum(r["median"] for r in rows) / len(rows), sum(r["worst"] for r in rows) / len(rows), len(rows))


def plots(opt, acc, sc):
    """Writes the two PNGs; returns their names (none without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        log("report: matplotlib missing (scripts/install_bench_deps.sh): no plots")
        return []
    names = []
    keys = [k for k, _, _ in METHODS if any(k in acc[s] for s in acc)]
    fig, ax = plt.subplots(figsize=(8, 3.6))
    width = 0.8 / max(1, len(keys))
    for j, key in enumerate(keys):
        cells = [suite_cell(acc[s].get(key)) for s in acc]
        xs = [i + j * width for i in range(len(acc))]
        ax.bar(xs, [c[0] if c else 0 for c in cells], width, label=dict((k, l) for k, l, _ in METHODS)[key],
               yerr=[[0] * len(cells), [(c[1] - c[0]) if c else 0 for c in cells]], capsize=3)
    ax.set_xticks([i + 0.4 - width / 2 for i in range(len(acc))], list(acc))
    ax.set_ylabel("% wrong (mean of per-file medians;\nbar to the worst seed)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(opt.results, "report_error_per_suite.png"), dpi=110)
    names.append("report_error_per_suite.png")
    fig, axs = plt.subplots(1, 2, figsize=(9, 3.4))
    for key, label, _ in METHODS:
        pts = [(r["points"], r[key]) for r in sc if key in r and r[key]["rc"] == 0]
        if pts:
            axs[0].loglog([p for p, _ in pts], [m["wall"] for _, m in pts], "o-", label=label)
            axs[1].loglog([p for p, _ in pts], [m["rss"] for _, m in pts], "o-", label=label)
    axs[0].set_ylabel("wall s (read, orient, write)")
    axs[1].set_ylabel("peak RSS MB")
    for a in axs:
        a.set_xlabel("points (generated room)")
    axs[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(opt.results, "report_time_memory.png"), dpi=110)
    names.append("report_time_memory.png")
    return names


def render(opt):
    """The two pictures; returns bench/render.sh's own summary lines."""
    lines = []
    for out, extra in (("room_dacpo_vs_peer.png", []), ("room_sign_colors.png", ["-sign"])):
        r = run(["bash", os.path.join(ROOT, "bench", "render.sh"), "-b", opt.build,
                 "-w", os.path.join(opt.work, "render"), "-o", os.path.join(opt.results, out)] + extra)
        if r.returncode != 0:
            log(r.stdout[-1000:] + r.stderr[-2000:])
            sys.exit("report: bench/render.sh failed (scripts/install_bench_deps.sh installs its tools)")
        lines.append(r.stdout.strip().splitlines()[-1].replace(ROOT + os.sep, ""))
    return lines


def machine():
    cpu = platform.processor() or "?"
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 30
    commit = run(["git", "-C", ROOT, "rev-parse", "--short=12", "HEAD"]).stdout.strip() or "?"
    dirty = " (with uncommitted changes)" if run(["git", "-C", ROOT, "status", "--porcelain", "--",
                                                   "c_core", "wrappers", "pcl_dacpo"]).stdout else ""
    return (f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, {cpu}, {os.cpu_count()} cores, "
            f"{mem:.1f} GiB, {platform.system()} {platform.release()}; commit {commit}{dirty}")


def fmt(v, spec=".2f"):
    return "—" if v is None else format(v, spec)


def per_file_table(acc, names):
    L = ["<details><summary>Every file</summary>", "",
          "| suite | file | points | pcl_dacpo median (worst) | in-block / flip | " +
          " | ".join(names[k] for k, _, p in METHODS if p and any(k in acc[s] for s in acc)) + " |",
          "|---|---|---:|---:|---:|" + "---:|" * sum(1 for k, _, p in METHODS
                                                   if p and any(k in acc[s] for s in acc))]
    for s in acc:
        for r in acc[s].get("dacpo", []):
            peers = []
            for k, _, p in METHODS:
                if p and any(k in acc[t] for t in acc):
                    m = next((x for x in acc[s].get(k, []) if x["file"] == r["file"]), None)
                    peers.append(fmt(m and m["median"]))
            L.append(f"| {s} | {r['file']} | {r['points']} | {r['median']:.2f} ({r['worst']:.2f}) | "
                     f"{r['in_block']:.2f} / {r['flip']:.2f} | " + " | ".join(peers) + " |")
    return L + ["", "</details>", ""]


def markdown(opt, acc, sc, pngs, pictures, command, stamp, per_file=True):
    """The results; per_file=False (the README) links report.md for the table of every file."""
    names = dict((k, l) for k, l, _ in METHODS)
    seeds = len([s for s in opt.seeds.split(",") if s])
    L = [f"Measured {stamp}; `{command}`.", "",
         f"**Error per suite** (% of normals wrong after one global sign flip, the paper's metric; "
         f"per file the median over seeds {opt.seeds} for pcl_dacpo, one run for the deterministic peers; "
         f"cell = mean over the suite's files, (worst seed) beside it; every method starts from unsigned "
         f"PCA normals, k = 16):", ""]
    L.append("| method | " + " | ".join(f"{s} ({len(acc[s].get('dacpo') or next(iter(acc[s].values())))})"
                                       for s in acc) + " |")
    L.append("|---|" + "---:|" * len(acc))
    for key, label, _ in METHODS:
        if not any(key in acc[s] for s in acc):
            continue
        cells = []
        for s in acc:
            c = suite_cell(acc[s].get(key))
            cells.append("—" if not c else (f"**{c[0]:.2f}** ({c[1]:.2f})" if key == "dacpo" and seeds > 1
                                             else f"{c[0]:.2f}"))
        L.append(f"| {label} | " + " | ".join(cells) + " |")
    L.append("")
    if any("dacpo" in acc[s] for s in acc):
        L.append("pcl_dacpo's error split (median runs, mean over files: in-block = stages 0–3, flip = "
                 "blocks flipped by stages 4–5, part = relative sign of disconnected parts): " + "; ".join(
                     f"{s} {sum(r['in_block'] for r in acc[s]['dacpo']) / len(acc[s]['dacpo']):.2f} / "
                     f"{sum(r['flip'] for r in acc[s]['dacpo']) / len(acc[s]['dacpo']):.2f} / "
                     f"{sum(r['component'] for r in acc[s]['dacpo']) / len(acc[s]['dacpo']):.2f}"
                     for s in acc if acc[s].get("dacpo")) + ".")
        L.append("")
    if per_file:
        L += per_file_table(acc, names)
    else:
        L += ["Every file, every method: [`bench/results/report.md`](bench/results/report.md).", ""]
    keys = [k for k, _, _ in METHODS if any(k in r for r in sc)]
    limit = opt.time_limit

    def cell(m):
        if m.get("skipped"):
            return "not run (slower before)"
        if m["rc"] == 124:
            return f"> {limit:.0f} s"
        if m["rc"]:
            return "failed"
        return f"{fmt(m['wall'], '.1f')} s / {fmt(m['rss'], '.0f')} MB / {fmt(m['wrong'])} %"
    L += ["**Time and peak memory against points** (generated room, scene seed 1; end to end: read, "
          "orient, write; pcl_dacpo on all cores, the peers as they run; cell = wall s / peak RSS MB / "
          f"% wrong; {limit:.0f} s at most per run):", "",
          "| points | " + " | ".join(names[k] for k in keys) + " |", "|---:|" + "---:|" * len(keys)]
    for r in sc:
        cells = [cell(r[k]) if k in r else "—" for k in keys]
        L.append(f"| {r['points']:,} | " + " | ".join(cells) + " |")
    L.append("")
    for p in pngs:
        L.append(f"![{p[:-4].replace('_', ' ')}](bench/results/{p})")
    L.append("")
    for line in pictures:  # "render: wrote PATH (caption)"
        m = re.match(r"render: wrote (\S+) \((.*)\)$", line)
        if m:
            name = os.path.basename(m.group(1))
            L += [f"![{m.group(2)}](bench/results/{name})", "",
                  f"`bench/render.sh`: {m.group(2)} (generated room, 100K points, scene and run seed 1).", ""]
    L.append("")
    return "\n".join(L)


def into_readme(text):
    path = os.path.join(ROOT, "README.md")
    s = open(path).read()
    if BEGIN not in s or END not in s:
        sys.exit(f"report: README.md has no {BEGIN} ... {END} block")
    a, b = s.index(BEGIN) + len(BEGIN), s.index(END)
    with open(path + ".tmp", "w") as fh:
        fh.write(s[:a] + "\n" + text + "\n" + s[b:])
    os.replace(path + ".tmp", path)


def main():
    opt = parse()
    # the suites' folders are this machine's: shown as DIR
    shown = [a for a in sys.argv[1:] if a not in ("--no-readme", "--rewrite")]
    command = re.sub(r"(--suite [\w.-]+)=\S+", r"\1=DIR", " ".join(["bench/report.sh"] + shown))
    os.makedirs(opt.work, exist_ok=True)
    os.makedirs(opt.results, exist_ok=True)
    if opt.rewrite:
        saved = json.load(open(os.path.join(opt.results, "report.json")))
        acc, sc, pictures = saved["accuracy"], saved["scaling"], saved["pictures"]
        command, opt.seeds, stamp = saved["command"], saved["seeds"], saved["machine"]
    else:
        stamp = machine()  # the code measured: the commit at the start
        found = tools_and_peers(opt)
        acc = accuracy(opt, found, suites(opt))
        sc = scaling(opt, found)
        pictures = [] if opt.no_render else render(opt)
    pngs = plots(opt, acc, sc)
    text = markdown(opt, acc, sc, pngs, pictures, command.strip(), stamp)
    with open(os.path.join(opt.results, "report.md"), "w") as fh:
        fh.write("# pcl_dacpo results (written by bench/report.sh)\n\n" + text.replace("](bench/results/", "]("))
    text = markdown(opt, acc, sc, pngs, pictures, command.strip(), stamp, per_file=False)
    with open(os.path.join(opt.results, "report.json"), "w") as fh:
        json.dump(dict(accuracy=acc, scaling=sc, pictures=pictures, machine=stamp, command=command,
                       seeds=opt.seeds), fh, indent=1)
    print(text)
    if not opt.no_readme:
        into_readme(text)
        log("# README.md block replaced")


if __name__ == "__main__":
    main()
