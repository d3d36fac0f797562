#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# pcl_dacpo benchmark suite: one command, a table in the paper's format.
#
#   bench/run_benchmark.sh                 # quick accuracy suite (~10-15 min on 2 cores)
#   bench/run_benchmark.sh --scaling       # quick scaling run: 50K .. 1M points
#   bench/run_benchmark.sh --all           # both
#   bench/run_benchmark.sh --full --all    # 500K rooms, 3 seeds, scaling up to 4M (hours)
#   bench/run_benchmark.sh --robustness [robustness.py options] [DIR ...]
#                                          # every ground-truth PLY of DIR (default:
#                                          # $DACPO_REAL_DATA and $DACPO_ROOMS_DATA) x
#                                          # seeds 1-5: median, worst, spread, error split
#
# Accuracy suite: generated rooms in the paper's variants (clean, Gaussian noise
# sigma 0.004 / 0.008, random downsampling to 100K / 10K) and every PLY in
# --data DIR or $DACPO_REAL_DATA when given (real scans with ground-truth
# normals; skipped with a note otherwise),
# oriented by pcl_dacpo (default), its ablations (-no_ipsr, -weights dipole,
# -blocks 1) and the peers that are installed (Open3D, CGAL, PCL viewpoint;
# scripts/install_bench_deps.sh), every method starting from unsigned PCA
# normals (k = 16) and scored by pcl_dacpo_eval against the ground truth.
# Scaling: pcl_dacpo on generated rooms of growing size, wall time, peak RSS,
# per-stage seconds, fitted slope and log-log exponent.
#
# Writes <results>/results.json (raw per-run records + summaries) and
# <results>/results.md (the tables); prints the tables on stdout.
# Options: bench/run_benchmark.sh -h
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if ! command -v python3 >/dev/null 2>&1; then
  echo "run_benchmark: python3 is needed (standard library only)" >&2
  exit 1
fi
if [ "${1:-}" = "--robustness" ]; then
  shift
  has_input=0
  for a in "$@"; do case "$a" in -*) ;; *) [ -e "$a" ] && has_input=1 ;; esac; done
  if [ "$has_input" = 0 ]; then
    for d in "${DACPO_REAL_DATA:-}" "${DACPO_ROOMS_DATA:-}"; do
      [ -n "$d" ] && set -- "$@" "$d"
    done
  fi
  exec python3 "$root/bench/robustness.py" "$@"
fi
exec python3 - "$root" "$@" <<'PY'
import json, math, os, platform, re, shlex, shutil, signal, subprocess, sys, time
from datetime import datetime, timezone

ROOT = sys.argv[1]
ARGS = sys.argv[2:]

USAGE = """usage: bench/run_benchmark.sh [options]
  --quick            sizes for ~10-15 min on 2 cores (default): rooms of 200K points,
                     1 seed, scaling 50K..1M
  --full             rooms of 500K points, seeds 1..3, scaling 50K..4M, long peer time limits
  --accuracy         run the accuracy suite (default when neither --scaling nor --all)
  --scaling          run the scaling suite only
  --all              run both
  --report           run nothing, rewrite results.md from results.json
  -b DIR             build directory (default: <repo>/build; configured and built if the tools
                     are missing)
  -w DIR             work directory for generated inputs and predictions (default: <build>/bench)
  -o DIR             results directory (default: <repo>/bench/results)
  --data DIR         real scans, every *.ply (default: $DACPO_REAL_DATA, unset = none)
  --no-real          skip the real scans
  --room-n N         points of the generated rooms before downsampling
  --seeds N          generated rooms per variant (seeds 1..N)
  --sizes "N N ..."  scaling sizes
  --methods LIST     comma list of: dacpo,no_ipsr,dipole,blocks1,open3d,cgal,pcl_viewpoint
                     (default: all)
  --extra LABEL=ARGS add a pcl_dacpo row with extra orient arguments, e.g.
                     --extra "pcl_dacpo -c 1.2=-c 1.2" (repeatable)
  --threads N        threads for every method (default: 0 = all cores)
  --timeout S        wall limit per run (default: quick 600, full 3600)
  --open3d-timeout S wall limit per Open3D run (default: quick 60, full 1800); after a time-out
                     Open3D is skipped on larger inputs of the same kind
  -h                 this text"""

opt = dict(mode="quick", what=None, build=os.path.join(ROOT, "build"), work=None,
           results=os.path.join(ROOT, "bench", "results"),
           data=os.environ.get("DACPO_REAL_DATA", ""), real=True,
           room_n=None, seeds=None, sizes=None, methods=None, extra=[], threads=0,
           timeout=None, o3d_timeout=None)
i = 0
try:
    while i < len(ARGS):
        a = ARGS[i]
        nxt = lambda: ARGS[i + 1]
        if a in ("-h", "--help"): print(USAGE); sys.exit(0)
        elif a == "--quick": opt["mode"] = "quick"
        elif a == "--full": opt["mode"] = "full"
        elif a == "--accuracy": opt["what"] = "accuracy"
        elif a == "--scaling": opt["what"] = "scaling"
        elif a == "--all": opt["what"] = "all"
        elif a == "--report": opt["what"] = "report"
        elif a == "--no-real": opt["real"] = False
        elif a in ("-b", "-w", "-o", "--data", "--room-n", "--seeds", "--sizes", "--methods",
                   "--extra", "--threads", "--timeout", "--open3d-timeout"):
            v = nxt(); i += 1
            if a == "-b": opt["build"] = os.path.abspath(v)
            elif a == "-w": opt["work"] = os.path.abspath(v)
            elif a == "-o": opt["results"] = os.path.abspath(v)
            elif a == "--data": opt["data"] = os.path.abspath(v)
            elif a == "--room-n": opt["room_n"] = int(v)
            elif a == "--seeds": opt["seeds"] = int(v)
            elif a == "--sizes": opt["sizes"] = [int(s) for s in v.replace(",", " ").split()]
            elif a == "--methods": opt["methods"] = [s for s in v.split(",") if s]
            elif a == "--extra":
                if "=" not in v: raise ValueError("--extra needs LABEL=ARGS")
                opt["extra"].append(tuple(v.split("=", 1)))
            elif a == "--threads": opt["threads"] = int(v)
            elif a == "--timeout": opt["timeout"] = float(v)
            elif a == "--open3d-timeout": opt["o3d_timeout"] = float(v)
        else:
            raise ValueError(f"unknown option {a}")
        i += 1
except (IndexError, ValueError) as e:
    print(f"run_benchmark: {e}\n{USAGE}", file=sys.stderr); sys.exit(2)

full = opt["mode"] == "full"
what = opt["what"] or "accuracy"
room_n = opt["room_n"] or (500000 if full else 200000)
seeds = opt["seeds"] or (3 if full else 1)
sizes = opt["sizes"] or ([50000, 100000, 250000, 500000, 1000000, 2000000, 4000000] if full
                         else [50000, 100000, 250000, 500000, 1000000])
timeout = opt["timeout"] or (3600.0 if full else 600.0)
o3d_timeout = opt["o3d_timeout"] or (1800.0 if full else 60.0)
build = opt["build"]
work = opt["work"] or os.path.join(build, "bench")
tools = os.path.join(build, "wrappers")
threads = opt["threads"]


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run_quiet(cmd, **kw):
    return subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, **kw)


# ---------------------------------------------------------------- tools and peers
def ensure_tools():
    need = ["dacpo_make_scene", "pcl_dacpo_orient", "pcl_dacpo_eval"]
    if all(os.access(os.path.join(tools, t), os.X_OK) for t in need):
        return
    log(f"# building pcl_dacpo in {build}")
    r = run_quiet(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release"])
    if r.returncode == 0:
        r = run_quiet(["cmake", "--build", build, "-j", str(os.cpu_count() or 2)])
    if r.returncode != 0 or not all(os.access(os.path.join(tools, t), os.X_OK) for t in need):
        log(r.stdout[-3000:])
        log("run_benchmark: could not build the tools (scripts/install_deps.sh installs what they need)")
        sys.exit(1)


notes = []


def find_open3d_python():
    for py in ("/usr/bin/python3", shutil.which("python3") or ""):
        if py and os.access(py, os.X_OK):
            r = run_quiet([py, "-c", "import open3d; print(open3d.__version__)"])
            if r.returncode == 0:
                return py, r.stdout.strip().splitlines()[-1]
    return None, None


def build_peers():
    """Builds bench/peers (CMake) into <work>/peers-build; returns {name: path}."""
    found = {}
    src = os.path.join(ROOT, "bench", "peers")
    out = os.path.join(work, "peers-build")
    r = run_quiet(["cmake", "-S", src, "-B", out, "-DCMAKE_BUILD_TYPE=Release"])
    if r.returncode == 0:
        r = run_quiet(["cmake", "--build", out, "-j", str(os.cpu_count() or 2)])
    if r.returncode != 0:
        notes.append("peer programs in bench/peers failed to build (see "
                     f"{out}); CGAL and PCL peers skipped")
        log(r.stdout[-3000:])
    for name in ("cgal_orient", "pcl_viewpoint"):
        p = os.path.join(out, name)
        if os.access(p, os.X_OK):
            found[name] = p
    return found


# ---------------------------------------------------------------- running one process
TIME = "/usr/bin/time" if os.access("/usr/bin/time", os.X_OK) else None


def parse_time_v(path):
    """GNU time -v output -> (wall s, user s, sys s, max RSS MB)."""
    wall = user = sys_ = rss = None
    try:
        txt = open(path).read()
    except OSError:
        return None
    for line in txt.splitlines():
        line = line.strip()
        if line.startswith("User time (seconds):"): user = float(line.split(":")[-1])
        elif line.startswith("System time (seconds):"): sys_ = float(line.split(":")[-1])
        elif line.startswith("Maximum resident set size (kbytes):"): rss = int(line.split(":")[-1]) / 1024.0
        elif line.startswith("Elapsed (wall clock) time"):
            v = line.split("):")[-1].strip().split(":")
            wall = sum(float(x) * 60 ** k for k, x in enumerate(reversed(v)))
    return wall, user, sys_, rss


def measure(cmd, log_path, limit, env=None):
    """Runs cmd with stderr+stdout to log_path, under /usr/bin/time -v when present.
    Returns dict(status, rc, wall_s, cpu_s, peak_rss_mb, rss_source)."""
    tfile = log_path + ".time"
    full_cmd = ([TIME, "-v", "-o", tfile] if TIME else []) + cmd
    t0 = time.perf_counter()
    with open(log_path, "w") as lf:
        p = subprocess.Popen(full_cmd, stdin=subprocess.DEVNULL, stdout=lf, stderr=lf,
                             start_new_session=True, env=env)
        status = "ok"
        deadline = t0 + limit
        while True:
            pid, st, ru = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                break
            if time.perf_counter() > deadline:
                os.killpg(p.pid, signal.SIGKILL)  # our own process group (time + tool)
                pid, st, ru = os.wait4(p.pid, 0)
                status = "timeout"
                break
            time.sleep(0.05)
        p.returncode = os.waitstatus_to_exitcode(st)
    wall = time.perf_counter() - t0
    res = dict(status=status, rc=p.returncode, wall_s=round(wall, 3), cpu_s=None,
               peak_rss_mb=None, rss_source=None)
    tv = parse_time_v(tfile) if (TIME and status == "ok") else None
    if tv and tv[3] is not None:
        res["wall_s"] = round(tv[0], 3) if tv[0] is not None else res["wall_s"]
        res["cpu_s"] = round((tv[1] or 0) + (tv[2] or 0), 3)
        res["peak_rss_mb"] = round(tv[3], 1)
        res["rss_source"] = "/usr/bin/time -v"
    elif status == "timeout":  # the killed tool was never waited for: no usage to report
        res["rss_source"] = None
    else:  # rusage of the waited process tree (Linux: kilobytes)
        res["cpu_s"] = round(ru.ru_utime + ru.ru_stime, 3)
        res["peak_rss_mb"] = round(ru.ru_maxrss / 1024.0, 1)
        res["rss_source"] = "wait4 rusage"
    if status == "ok" and res["rc"] != 0:
        res["status"] = "failed"
    return res


def stats_line(log_path):
    """Last 'stats: k=v ...' line of a tool's stderr -> dict."""
    out = {}
    try:
        lines = open(log_path, errors="replace").read().splitlines()
    except OSError:
        return out
    for line in reversed(lines):
        if line.startswith("stats:"):
            for kv in line[6:].split():
                if "=" in kv:
                    k, v = kv.split("=", 1)
                    try:
                        out[k] = int(v)
                    except ValueError:
                        try:
                            out[k] = float(v)
                        except ValueError:
                            out[k] = v
            break
    return out


def stage_times(log_path):
    """'Stage times [s]: input 0.003 neighbors 0.151 ... | total 4.100' -> dict."""
    try:
        txt = open(log_path, errors="replace").read()
    except OSError:
        return {}
    m = None
    for m in re.finditer(r"Stage times \[s\]:(.*)", txt):
        pass
    if not m:
        return {}
    toks = m.group(1).replace("|", " ").split()
    return {toks[k]: float(toks[k + 1]) for k in range(0, len(toks) - 1, 2)
            if re.match(r"^[0-9.eE+-]+$", toks[k + 1])}


def evaluate(gt, pred):
    r = run_quiet([os.path.join(tools, "pcl_dacpo_eval"), gt, pred, "-json"])
    for line in reversed(r.stdout.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                break
    return {"eval_error": r.stdout.strip()[-500:]}


def fmt_n(n):
    return f"{n // 1000000}M" if n >= 1000000 and n % 1000000 == 0 else (
        f"{n / 1e6:g}M" if n >= 1000000 else f"{n // 1000}K")


# ---------------------------------------------------------------- machine / provenance
def machine_info():
    cpu = platform.processor() or ""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip(); break
    except OSError:
        pass
    mem_gb = None
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem_gb = round(int(line.split()[1]) / 1024 / 1024, 1); break
    except OSError:
        pass
    commit = None
    try:  # read-only look at .git, no git command needed
        head = open(os.path.join(ROOT, ".git", "HEAD")).read().strip()
        if head.startswith("ref:"):
            ref = head[4:].strip()
            rp = os.path.join(ROOT, ".git", ref)
            if os.path.exists(rp):
                commit = open(rp).read().strip()
            else:
                for line in open(os.path.join(ROOT, ".git", "packed-refs")):
                    if line.strip().endswith(ref):
                        commit = line.split()[0]
        else:
            commit = head
    except OSError:
        pass
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = None
    return dict(date=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                host=platform.node(), os=f"{platform.system()} {platform.release()}",
                cpu=cpu, cores=os.cpu_count(), mem_gb=mem_gb, commit=commit[:12] if commit else None,
                load_at_start=load, mode=opt["mode"],
                command="bench/run_benchmark.sh " + " ".join(shlex.quote(a) for a in ARGS),
                peak_rss_from="/usr/bin/time -v" if TIME else "wait4 rusage")


# ---------------------------------------------------------------- inputs
def gen_scene(name, args):
    path = os.path.join(work, "in", name + ".ply")
    if not os.path.exists(path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        tmp = path[:-len(".ply")] + ".tmp.ply"  # the generator wants a .ply name
        r = run_quiet([os.path.join(tools, "dacpo_make_scene"), tmp] + args)
        if r.returncode != 0:
            log(r.stdout); sys.exit(f"run_benchmark: dacpo_make_scene failed for {name}")
        os.replace(tmp, path)
    return path


def ply_points(path):
    with open(path, "rb") as f:
        head = f.read(4096).decode("latin-1")
    m = re.search(r"element vertex (\d+)", head)
    return int(m.group(1)) if m else None


VARIANTS = [  # key, column title, generator arguments beyond -n/-seed
    ("clean", "Clean", []),
    ("noise004", "σ=0.004", ["-noise", "0.004"]),
    ("noise008", "σ=0.008", ["-noise", "0.008"]),
    ("ds100k", "100K", ["-downsample", "100000"]),
    ("ds10k", "10K", ["-downsample", "10000"]),
]


def accuracy_inputs():
    items = []
    for key, _, extra in VARIANTS:
        if "-downsample" in extra and int(extra[extra.index("-downsample") + 1]) >= room_n:
            notes.append(f"variant {key} skipped: the room has only {room_n} points")
            continue
        for s in range(1, seeds + 1):
            name = f"room{fmt_n(room_n)}_{key}_s{s}"
            path = gen_scene(name, ["-scene", "room", "-n", str(room_n), "-seed", str(s)] + extra)
            items.append(dict(name=name, path=path, kind="gen", variant=key, points=ply_points(path)))
    if opt["real"]:
        if os.path.isdir(opt["data"]):
            plys = sorted(f for f in os.listdir(opt["data"]) if f.lower().endswith(".ply"))
            for f in plys:
                p = os.path.join(opt["data"], f)
                items.append(dict(name=os.path.splitext(f)[0], path=p, kind="real", variant="real",
                                  points=ply_points(p)))
            if not plys:
                notes.append(f"no *.ply in {opt['data']}: real-scan column empty")
        else:
            notes.append(f"{opt['data'] or 'no --data DIR / DACPO_REAL_DATA'}: real scans skipped")
    else:
        notes.append("real scans skipped (--no-real)")
    return items


# ---------------------------------------------------------------- methods
def method_table(peers, o3d_py):
    orient = os.path.join(tools, "pcl_dacpo_orient")
    th = ["-threads", str(threads)]

    def dacpo(extra):
        return lambda i, o: [orient, i, o, "-estimate", "-q"] + th + extra

    ms = [
        dict(key="dacpo", label="pcl_dacpo (default)", ext="pcd", cmd=dacpo([])),
        dict(key="no_ipsr", label="pcl_dacpo, no iPSR (`-no_ipsr`)", ext="pcd", cmd=dacpo(["-no_ipsr"])),
        dict(key="dipole", label="pcl_dacpo, dipole weights (`-weights dipole`)", ext="pcd",
             cmd=dacpo(["-weights", "dipole"])),
        dict(key="blocks1", label="pcl_dacpo, one block (`-blocks 1`)", ext="pcd", cmd=dacpo(["-blocks", "1"])),
    ]
    for n, (label, args) in enumerate(opt["extra"]):
        ms.append(dict(key=f"extra{n + 1}", label=label, ext="pcd", cmd=dacpo(shlex.split(args))))
    if o3d_py:
        ms.append(dict(key="open3d", label="Open3D tangent-plane MST (k=10)", ext="ply",
                       cmd=lambda i, o: [o3d_py, os.path.join(ROOT, "bench", "peers", "open3d_orient.py"),
                                         i, o, "-k", "10", "-normal_k", "16"]
                       + (["-threads", str(threads)] if threads else [])))
    if "cgal_orient" in peers:
        ms.append(dict(key="cgal", label="CGAL mst_orient_normals (k=10)", ext="ply",
                       cmd=lambda i, o: [peers["cgal_orient"], i, o, "-k", "10", "-normal_k", "16"]))
    if "pcl_viewpoint" in peers:
        ms.append(dict(key="pcl_viewpoint", label="PCL flip towards viewpoint = centroid", ext="ply",
                       cmd=lambda i, o: [peers["pcl_viewpoint"], i, o, "-normal_k", "16"]
                       + (["-threads", str(threads)] if threads else [])))
    if opt["methods"]:
        keep = set(opt["methods"]) | {m["key"] for m in ms if m["key"].startswith("extra")}
        ms = [m for m in ms if m["key"] in keep]
    return ms


def run_accuracy(meta):
    inputs = accuracy_inputs()
    peers = build_peers()
    o3d_py, o3d_ver = find_open3d_python()
    want = set(opt["methods"] or ["open3d", "cgal", "pcl_viewpoint"])
    if not o3d_py and "open3d" in want:
        notes.append("Open3D peer skipped: python3-open3d not installed (scripts/install_bench_deps.sh)")
    if "cgal_orient" not in peers and "cgal" in want:
        notes.append("CGAL peer skipped: libcgal-dev not installed or bench/peers did not build")
    if "pcl_viewpoint" not in peers and "pcl_viewpoint" in want:
        notes.append("PCL viewpoint peer skipped: PCL development files not found")
    if o3d_ver:
        meta["open3d_version"] = o3d_ver
    methods = method_table(peers, o3d_py)
    # Open3D 0.16's orientation can be far superlinear on exactly planar parts
    # (isl-org/Open3D#6482): run inputs smallest first and stop a kind after a time-out.
    order = sorted(inputs, key=lambda it: (it["kind"] != "gen", it["points"] or 0))
    total = len(order) * len(methods)
    runs, done = [], 0
    o3d_timed_out = {}  # kind -> smallest size that timed out
    for m in methods:
        for it in order:
            done += 1
            rec = dict(input=it["name"], path=it["path"], kind=it["kind"], variant=it["variant"],
                       points=it["points"], method=m["key"], label=m["label"])
            outdir = os.path.join(work, "runs", m["key"])
            os.makedirs(outdir, exist_ok=True)
            pred = os.path.join(outdir, f"{it['name']}.{m['ext']}")
            logp = os.path.join(outdir, f"{it['name']}.log")
            if os.path.exists(pred):
                os.remove(pred)
            lim = o3d_timeout if m["key"] == "open3d" else timeout
            if m["key"] == "open3d" and it["kind"] in o3d_timed_out and \
                    (it["points"] or 0) >= o3d_timed_out[it["kind"]]:
                rec.update(status="skipped",
                           note=f"not run: timed out at {o3d_timed_out[it['kind']]} points (limit {lim:g} s)")
            else:
                cmd = m["cmd"](it["path"], pred)
                rec["command"] = " ".join(shlex.quote(c) for c in cmd)
                rec.update(measure(cmd, logp, lim))
                rec["tool_stats"] = stats_line(logp)
                if rec["status"] == "ok" and os.path.exists(pred):
                    rec.update(evaluate(it["path"], pred))
                    if "wrong_pct" not in rec:
                        rec["status"] = "eval_failed"
                elif rec["status"] == "ok":
                    rec["status"] = "failed"
                if rec["status"] == "timeout":
                    rec["note"] = f"time limit {lim:g} s"
                    if m["key"] == "open3d":
                        o3d_timed_out[it["kind"]] = min(o3d_timed_out.get(it["kind"], 1 << 62),
                                                        it["points"] or 0)
                if rec["status"] == "failed":
                    try:
                        rec["note"] = open(logp, errors="replace").read().strip().splitlines()[-1][:200]
                    except (OSError, IndexError):
                        rec["note"] = "failed"
                un = rec.get("tool_stats", {}).get("unoriented")
                if isinstance(un, int) and it["points"]:
                    rec["unoriented"] = un
                    rec["unoriented_pct"] = round(100.0 * un / it["points"], 3)
            rec.pop("file", None)
            runs.append(rec)
            with open(os.path.join(outdir, f"{it['name']}.json"), "w") as f:
                json.dump(rec, f)
            w = f"{rec['wrong_pct']:.2f}% wrong" if "wrong_pct" in rec else rec["status"]
            t = f", {rec['wall_s']:.1f} s, {rec['peak_rss_mb']:.0f} MB" if rec.get("peak_rss_mb") else ""
            log(f"[{done}/{total}] {m['key']:<13} {it['name']:<28} {w}{t}")
    return dict(meta=meta, settings=dict(room_points=room_n, seeds=seeds, timeout_s=timeout,
                                         open3d_timeout_s=o3d_timeout, threads=threads,
                                         normal_k=16, peer_k=10,
                                         variants=[v[0] for v in VARIANTS]),
                methods=[dict(key=m["key"], label=m["label"]) for m in methods],
                notes=list(notes), runs=runs)


# ---------------------------------------------------------------- summaries
def mean(xs):
    return sum(xs) / len(xs) if xs else None


def accuracy_markdown(acc):
    runs, methods, meta, st = acc["runs"], acc["methods"], acc["meta"], acc["settings"]
    vt = dict((k, t) for k, t, _ in VARIANTS)
    n_real = len({r["input"] for r in runs if r["kind"] == "real"})

    def cell_vals(mk, v):
        sel = [r for r in runs if r["method"] == mk and r["variant"] == v]
        ok = [r["wrong_pct"] for r in sel if "wrong_pct" in r]
        return ok, len(sel)

    def cell(mk, v):
        ok, n = cell_vals(mk, v)
        if not n:
            return "—", None
        if not ok:
            stt = {r["status"] for r in runs if r["method"] == mk and r["variant"] == v}
            if "timeout" in stt:
                lim = st["open3d_timeout_s"] if mk == "open3d" else st["timeout_s"]
                return f"> {lim:g} s", None
            return ("not run" if stt == {"skipped"} else "failed"), None
        m = mean(ok)
        return (f"{m:.2f}" if len(ok) == n else f"{m:.2f} ({len(ok)}/{n})"), (m if len(ok) == n else None)

    L = []
    L.append(f"### Mean % of wrongly oriented normals (lower is better)\n")
    L.append(f"Generated room: {fmt_n(st['room_points'])} points, {st['seeds']} seed(s) per variant; "
             f"100K / 10K are random subsets of the {fmt_n(st['room_points'])} room. "
             f"Real scans: {n_real} PLY files (mean over files). "
             "Every method starts from unsigned PCA normals (k = 16) and is scored after one global "
             "sign flip (paper metric; points of small disconnected parts count too).\n")
    head = ["Method", "Clean", "σ=0.004", "σ=0.008", "Avg (noise)", "100K", "10K", "Avg (sparse)",
            f"Real scans ({n_real})"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|---|" + "---:|" * (len(head) - 1))
    best = {}
    table = []
    for m in methods:
        row, vals = [m["label"]], {}
        for v in ("clean", "noise004", "noise008", "AVG_N", "ds100k", "ds10k", "AVG_S", "real"):
            if v == "AVG_N" or v == "AVG_S":
                ks = ("clean", "noise004", "noise008") if v == "AVG_N" else ("clean", "ds100k", "ds10k")
                xs = [vals.get(k) for k in ks]
                if all(x is not None for x in xs):
                    vals[v] = mean(xs); row.append(f"{vals[v]:.2f}")
                else:
                    row.append("—")
            else:
                txt, val = cell(m["key"], v)
                if v == "real" and not n_real:
                    txt = "—"
                vals[v] = val; row.append(txt)
        table.append((row, vals))
        for k, x in vals.items():
            if x is not None and (k not in best or x < best[k]):
                best[k] = x
    keys = ("clean", "noise004", "noise008", "AVG_N", "ds100k", "ds10k", "AVG_S", "real")
    for row, vals in table:
        out = [row[0]]
        for j, k in enumerate(keys):
            t = row[j + 1]
            if vals.get(k) is not None and abs(vals[k] - best[k]) < 1e-9 and len(methods) > 1:
                t = f"**{t}**"
            out.append(t)
        L.append("| " + " | ".join(out) + " |")
    L.append("")
    cg = [r for r in runs if r["method"] == "cgal" and "unoriented_pct" in r]
    if cg:
        parts = []
        for v, title in list(vt.items()) + [("real", "real scans")]:
            xs = [r["unoriented_pct"] for r in cg if r["variant"] == v]
            if xs:
                parts.append(f"{title} {mean(xs):.1f}%")
        L.append("CGAL `mst_orient_normals` left points unoriented (not reachable from its seed, the "
                 "highest point; they keep the arbitrary PCA sign and are scored as they are): mean "
                 + ", ".join(parts) + ".\n")
    if any(m["key"] == "pcl_viewpoint" for m in methods):
        L.append("PCL viewpoint: no sensor position is known for these clouds, so the viewpoint is the "
                 "centroid of the cloud — what a user without a sensor position would do.\n")
    if any(m["key"] == "open3d" for m in methods):
        L.append(f"Open3D: `estimate_normals(KNN 16)` + `orient_normals_consistent_tangent_plane(10)`, "
                 f"time limit {st['open3d_timeout_s']:g} s per run; Open3D 0.16's orientation is far "
                 "superlinear on exactly planar synthetic surfaces (isl-org/Open3D#6482), so after a "
                 "time-out (\"> N s\") it is not run on larger inputs of the same kind (\"not run\"); "
                 "(k/n) = mean over the k of n inputs it finished.\n")

    L.append("### Time and peak memory (mean wall seconds end to end incl. file I/O / max peak RSS MB)\n")
    head2 = ["Method", "Clean", "σ=0.004", "σ=0.008", "100K", "10K", f"Real scans ({n_real})"]
    L.append("| " + " | ".join(head2) + " |")
    L.append("|---|" + "---:|" * (len(head2) - 1))
    for m in methods:
        row = [m["label"]]
        for v in ("clean", "noise004", "noise008", "ds100k", "ds10k", "real"):
            sel = [r for r in runs if r["method"] == m["key"] and r["variant"] == v and r["status"] == "ok"]
            if sel:
                row.append(f"{mean([r['wall_s'] for r in sel]):.1f} s / "
                           f"{max(r['peak_rss_mb'] or 0 for r in sel):.0f} MB")
            else:
                row.append("—")
        L.append("| " + " | ".join(row) + " |")
    L.append("")
    if acc.get("notes"):
        L.append("Notes: " + "; ".join(acc["notes"]) + ".\n")

    L.append("<details><summary>Every run</summary>\n")
    L.append("| input | points | method | % wrong | % wrong, largest comp. | comps | wall s | orient s | peak MB | note |")
    L.append("|---|---:|---|---:|---:|---:|---:|---:|---:|---|")
    for r in sorted(runs, key=lambda r: (r["kind"] != "gen", r["input"], r["method"])):
        ts = r.get("tool_stats", {})
        note = r.get("note", "")
        if "unoriented" in r:
            note = (note + "; " if note else "") + f"unoriented {r['unoriented']} ({r['unoriented_pct']:.1f}%)"
        if r["status"] not in ("ok",) and not note:
            note = r["status"]
        L.append(f"| {r['input']} | {r['points']} | {r['method']} | "
                 f"{r['wrong_pct']:.2f} | {r['largest_component_wrong_pct']:.2f} | {r.get('components', '')} | "
                 if "wrong_pct" in r else f"| {r['input']} | {r['points']} | {r['method']} | — | — | | ")
        L[-1] += (f"{r['wall_s']:.1f} | " if r.get("wall_s") is not None else "| ") + \
                 (f"{ts['seconds']:.2f} | " if isinstance(ts.get("seconds"), (int, float)) else "| ") + \
                 (f"{r['peak_rss_mb']:.0f} | " if r.get("peak_rss_mb") else "| ") + f"{note} |"
    L.append("\n</details>\n")
    return "\n".join(L)


def fit_line(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx == 0:
        return None, None
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return b, my - b * mx


# ---------------------------------------------------------------- scaling
STAGES = ["input", "neighbors", "normals", "segment", "dipole", "ipsr", "edge_weights", "ilp"]


def run_scaling(meta):
    orient = os.path.join(tools, "pcl_dacpo_orient")
    rows = []
    for k, n in enumerate(sizes):
        name = f"room{fmt_n(n)}_s1"
        path = gen_scene(name, ["-scene", "room", "-n", str(n), "-seed", "1"])
        outdir = os.path.join(work, "scaling")
        os.makedirs(outdir, exist_ok=True)
        pred = os.path.join(outdir, name + ".pcd")
        logp = os.path.join(outdir, name + ".log")
        # no -q: the tool prints "Stage times [s]: ..." (the progress bar stays off: stderr is a file)
        cmd = [orient, path, pred, "-estimate", "-threads", str(threads)]
        rec = dict(input=name, points=n, command=" ".join(shlex.quote(c) for c in cmd))
        rec.update(measure(cmd, logp, timeout))
        rec["tool_stats"] = stats_line(logp)
        rec["stages"] = stage_times(logp)
        if rec["status"] == "ok" and os.path.exists(pred):
            ev = evaluate(path, pred)
            rec["wrong_pct"] = ev.get("wrong_pct")
        try:
            os.remove(pred)
        except OSError:
            pass
        rows.append(rec)
        with open(os.path.join(outdir, name + ".json"), "w") as f:
            json.dump(rec, f)
        log(f"[scaling {k + 1}/{len(sizes)}] {fmt_n(n):>5}: {rec['status']}, {rec['wall_s']:.1f} s, "
            f"{rec['peak_rss_mb'] or 0:.0f} MB")
    ok = [r for r in rows if r["status"] == "ok"]
    fit = {}
    if len(ok) >= 2:
        xs = [r["points"] for r in ok]
        for key in ("wall_s", "peak_rss_mb"):
            ys = [r[key] for r in ok]
            b, a = fit_line(xs, ys)
            e, _ = fit_line([math.log(x) for x in xs], [math.log(max(y, 1e-9)) for y in ys])
            fit[key] = dict(per_100k=round(b * 1e5, 4), intercept=round(a, 3), loglog_exponent=round(e, 3))
    budget = []
    for n, lim in ((500000, 60.0), (1000000, 150.0)):
        r = next((r for r in rows if r["points"] == n), None)
        if r:
            budget.append(dict(points=n, what="wall s", limit=lim, value=r["wall_s"],
                               met=r["status"] == "ok" and r["wall_s"] <= lim))
    r = next((r for r in rows if r["points"] == 4000000), None)
    if r:
        budget.append(dict(points=4000000, what="peak RSS MB", limit=8192.0, value=r["peak_rss_mb"],
                           met=r["status"] == "ok" and (r["peak_rss_mb"] or 1e18) <= 8192.0))
    return dict(meta=meta, sizes=sizes, threads=threads, runs=rows, fit=fit, budget=budget)


def scaling_markdown(sc):
    L = ["### Scaling: pcl_dacpo (default) on generated rooms\n",
         "Wall = end to end (read, orient, write) from " + sc["meta"]["peak_rss_from"] +
         "; orient = the tool's own time; stages in seconds.\n"]
    head = ["points", "wall s", "orient s", "peak RSS MB", "blocks"] + STAGES + ["% wrong"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---:|" * len(head))
    for r in sc["runs"]:
        ts, sg = r.get("tool_stats", {}), r.get("stages", {})
        cells = [fmt_n(r["points"]), f"{r['wall_s']:.1f}" + ("" if r["status"] == "ok" else f" ({r['status']})"),
                 f"{ts['seconds']:.1f}" if isinstance(ts.get("seconds"), (int, float)) else "—",
                 f"{r['peak_rss_mb']:.0f}" if r.get("peak_rss_mb") else "—", str(ts.get("blocks", "—"))]
        cells += [f"{sg[s]:.2f}" if s in sg else "—" for s in STAGES]
        cells.append(f"{r['wrong_pct']:.2f}" if isinstance(r.get("wrong_pct"), (int, float)) else "—")
        L.append("| " + " | ".join(cells) + " |")
    L.append("")
    # the work inside stages 2-3, from the tool's stats line
    L.append("Work inside stages 2–3 (the tool's stats line): stage-2 restarts run "
             "(blocks that ran them all; the others stopped after four that agreed), "
             "stage-3 iterations per block, CG steps, faces queried and voted, and "
             "iterations whose solve left the surface as it was.\n")
    head = ["points", "restarts (blocks, all)", "iPSR iterations / block", "CG steps",
            "faces voted", "surfaces kept"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---:|" * len(head))
    for r in sc["runs"]:
        ts = r.get("tool_stats", {})
        if "restarts" not in ts:
            continue
        L.append("| " + " | ".join([
            fmt_n(r["points"]), f"{ts['restarts']} ({ts.get('blocks', '—')}, {ts.get('blocks_all_restarts', '—')})",
            f"{ts.get('ipsr_iterations_mean', 0):.2f}", str(ts.get("ipsr_cg_steps", "—")),
            str(ts.get("ipsr_faces", "—")), str(ts.get("ipsr_reused", "—"))]) + " |")
    L.append("")
    f = sc.get("fit", {})
    if f:
        w, m = f.get("wall_s"), f.get("peak_rss_mb")
        L.append(f"Least-squares fit over the finished runs: **{w['per_100k']:.2f} s per 100K points** "
                 f"(log-log exponent {w['loglog_exponent']:.2f}; 1.0 = linear), "
                 f"**{m['per_100k']:.0f} MB per 100K points** (exponent {m['loglog_exponent']:.2f}).\n")
    for b in sc.get("budget", []):
        L.append(f"- Budget {fmt_n(b['points'])}: {b['what']} {b['value']} ≤ {b['limit']:g} → "
                 f"{'met' if b['met'] else 'NOT met'}")
    L.append("")
    return "\n".join(L)


def meta_markdown(meta):
    load = f"{meta['load_at_start']:.2f}" if meta.get("load_at_start") is not None else "?"
    if meta.get("load_at_end") is not None:
        load += f" at start, {meta['load_at_end']:.2f} at end"
    s = (f"Run {meta['date']} on {meta['cpu']} ({meta['cores']} cores, {meta['mem_gb']} GiB), "
         f"{meta['os']}; commit {meta['commit'] or '?'}; load average (1 min) {load}; "
         f"command `{meta['command']}`.")
    return s


# ---------------------------------------------------------------- main
def portable(obj):
    """Results name paths relative to <work>, <build>, <data> and <repo>, so the
    committed JSON carries no machine's absolute paths."""
    prefixes = [(os.path.abspath(work), "<work>"), (os.path.abspath(build), "<build>"),
                (os.path.abspath(opt["data"]), "<data>") if opt.get("data") else None,
                (os.path.abspath(ROOT), "<repo>")]
    prefixes = [p for p in prefixes if p]
    if isinstance(obj, dict):
        return {k: portable(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [portable(v) for v in obj]
    if isinstance(obj, str):
        for path, name in prefixes:
            obj = obj.replace(path, name)
        return obj
    return obj


def main():
    if what != "report":
        ensure_tools()
        os.makedirs(work, exist_ok=True)
    os.makedirs(opt["results"], exist_ok=True)
    rj = os.path.join(opt["results"], "results.json")
    try:
        allres = json.load(open(rj))
    except (OSError, ValueError):
        allres = {}
    if what == "report" and not allres:
        sys.exit(f"run_benchmark: no results in {rj}")
    meta = machine_info()
    if what in ("accuracy", "all"):
        allres["accuracy"] = run_accuracy(dict(meta))
    if what in ("scaling", "all"):
        allres["scaling"] = run_scaling(dict(meta))
    for sec in ("accuracy", "scaling"):
        if what in (sec, "all"):
            try:
                allres[sec]["meta"]["load_at_end"] = os.getloadavg()[0]
            except OSError:
                pass
    allres = portable(allres)  # results.md too: no machine's paths
    with open(rj + ".tmp", "w") as f:
        json.dump(allres, f, indent=1)
    os.replace(rj + ".tmp", rj)
    md = ["# pcl_dacpo benchmark results\n",
          "Written by `bench/run_benchmark.sh` (see bench/README.md); raw records in results.json.\n"]
    if "accuracy" in allres:
        md += ["## Accuracy\n", meta_markdown(allres["accuracy"]["meta"]) + "\n",
               accuracy_markdown(allres["accuracy"])]
    if "scaling" in allres:
        md += ["## Scaling\n", meta_markdown(allres["scaling"]["meta"]) + "\n",
               scaling_markdown(allres["scaling"])]
    text = "\n".join(md)
    with open(os.path.join(opt["results"], "results.md"), "w") as f:
        f.write(text)
    # stdout: the tables of this invocation (without the long per-run list)
    if what == "report":
        print(re.sub(r"<details>.*?</details>\n", "", text, flags=re.S))
        return
    out = [meta_markdown(meta) + "\n"]
    if what in ("accuracy", "all"):
        out.append(accuracy_markdown(allres["accuracy"]).split("<details>")[0])
    if what in ("scaling", "all"):
        out.append(scaling_markdown(allres["scaling"]))
    print("\n".join(out))
    log(f"# wrote {rj} and {os.path.join(opt['results'], 'results.md')}")


main()
PY
