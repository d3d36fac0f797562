#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The documents' parameter tables, written from the one parameter table
(c_core/include/dacpo/dacpo_param_table.h): field, command-line option,
default and contract of every row. A block between
"<!-- scripts/param_table.py: begin USER -->" (or EXPERT) and
"<!-- scripts/param_table.py: end -->" gets the rows of that audience: the
README has the USER rows, docs/PARAMETERS.md the method switches. In the
Python stub (wrappers/python/pcl_dacpo/__init__.pyi) the block between
"# scripts/param_table.py: begin KEYWORDS" and "# scripts/param_table.py: end"
gets orient()'s keyword of every row (the package takes all but
estimate_normals and keep_mesh, which it sets itself).

  scripts/param_table.py                 print both tables
  scripts/param_table.py --write F...    fill every block of each file
  scripts/param_table.py --check F...    exit 1 when a block differs (a test)
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADER = os.path.join(ROOT, "c_core", "include", "dacpo", "dacpo_param_table.h")
BEGIN = re.compile(r"(?:<!--|#) scripts/param_table.py: begin (USER|EXPERT|KEYWORDS)(?: -->)?")
END = re.compile(r"[ \t]*(?:<!--|#) scripts/param_table.py: end")
NOT_KEYWORDS = ("estimate_normals", "keep_mesh")
PY_TYPES = {"SIZE": "int", "INT": "int", "UINT": "int", "U64": "int", "REAL": "float",
            "FLAG": "bool", "ENUM": "Union[str, int]"}
TITLES = {"USER": "Set by users", "EXPERT": "Method switches (for measurement and ablation)"}
ROW = re.compile(r'DACPO_PARAM\((\w+), \w+, (\w+), ([^,]+), ([^,]+), ([^,]+), (USER|EXPERT), '
                 r'(VALUE|SPECIAL|NONE), "([^"]*)",\s*\\?\s*"([^"]*)"\)')


def rows():
    text = open(HEADER, encoding="utf-8").read()
    text = text[text.index("#define DACPO_PARAMS_BEFORE_VIEWPOINT()"):]
    found = ROW.findall(text)
    if not found:
        sys.exit(f"param_table: no rows found in {HEADER}")
    return found


def default_text(kind, value):
    if kind == "ENUM":  # DACPO_WEIGHT_VCR -> vcr, DACPO_SIGN_FREE_SPACE -> free_space
        return value.split("_", 2)[2].lower()
    if kind == "REAL":
        v = float(value)
        return str(int(v)) if v == int(v) else repr(v)
    return value


def range_text(kind, lo, hi):
    """The accepted range as the tables show it."""
    if kind in ("ENUM", "FLAG"):
        return "0 or 1" if kind == "FLAG" else "—"
    inf = lambda v: v.strip().lstrip("-") == "DACPO_INF"
    if inf(lo) and inf(hi):
        return "any"
    if inf(hi):
        return f"≥ {lo}"
    return f"[{lo}, {hi}]"


def keywords():
    out = []
    for kind, name, value, lo, hi, audience, cli, flag, doc in rows():
        if name not in NOT_KEYWORDS:
            out.append(f"    {name}: {PY_TYPES[kind]} = ...,")
    return "\n".join(out) + "\n"


def block_text(who):
    """What goes between the markers of a block for \a who."""
    return keywords() if who == "KEYWORDS" else markdown(who) + "\n"


def markdown(who):
    out = [f"**{TITLES[who]}**", "", "| field | CLI | default | range | contract |",
           "|---|---|---|---|---|"]
    for kind, name, value, lo, hi, audience, cli, flag, doc in rows():
        if audience != who:
            continue
        shown = ", ".join(f"`{f.strip()}`" for f in flag.split(",")) if flag else "—"
        out.append(f"| `{name}` | {shown} | {default_text(kind, value)} | "
                   f"{range_text(kind, lo, hi)} | {doc} |")
    return "\n".join(out) + "\n"


def filled(path):
    """The file's text with every block filled in; exits if it has none."""
    text = open(path, encoding="utf-8").read()
    out, pos, blocks = [], 0, 0
    for m in BEGIN.finditer(text):
        e = END.search(text, m.end())
        if not e:
            sys.exit(f"param_table: {path}: no end marker after {m.group(0)}")
        out += [text[pos:m.end()], "\n" + block_text(m.group(1))]
        pos, blocks = e.start(), blocks + 1
    if not blocks:
        sys.exit(f"param_table: {path} has no scripts/param_table.py block")
    return text, "".join(out) + text[pos:]


def main(argv):
    if len(argv) == 1:
        print(markdown("USER") + "\n" + markdown("EXPERT"))
        return 0
    if len(argv) < 3 or argv[1] not in ("--write", "--check"):
        print(__doc__, file=sys.stderr)
        return 2
    status = 0
    for path in argv[2:]:
        text, wanted = filled(path)
        if argv[1] == "--check":
            if text != wanted:
                print(f"param_table: the parameter table in {path} is not the one "
                      f"dacpo_param_table.h gives; run scripts/param_table.py --write {path}",
                      file=sys.stderr)
                status = 1
            continue
        with open(path + ".tmp", "w", encoding="utf-8") as fh:
            fh.write(wanted)
        os.replace(path + ".tmp", path)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
