#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The README's parameter tables, written from the one parameter table
(c_core/include/dacpo/dacpo_param_table.h): field, command-line option,
default and contract of every row, the USER rows first.

  scripts/param_table.py              print the tables
  scripts/param_table.py --write F    replace the block of F between its
                                      "scripts/param_table.py" markers
  scripts/param_table.py --check F    exit 1 when that block differs (a test)
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADER = os.path.join(ROOT, "c_core", "include", "dacpo", "dacpo_param_table.h")
BEGIN = "<!-- scripts/param_table.py: begin -->"
END = "<!-- scripts/param_table.py: end -->"
ROW = re.compile(r'DACPO_PARAM\((\w+), (\w+), ([^,]+), (USER|EXPERT), (VALUE|SPECIAL|NONE), '
                 r'"([^"]*)",\s*\\?\s*"([^"]*)"\)')


def rows():
    text = open(HEADER, encoding="utf-8").read()
    text = text[text.index("#define DACPO_PARAMS()"):]
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


def markdown():
    out = []
    for who, title in (("USER", "Set by users"), ("EXPERT", "Method switches (for measurement and ablation)")):
        out += [f"**{title}**", "", "| field | CLI | default | contract |", "|---|---|---|---|"]
        for kind, name, value, audience, cli, flag, doc in rows():
            if audience != who:
                continue
            shown = ", ".join(f"`{f.strip()}`" for f in flag.split(",")) if flag else "—"
            out.append(f"| `{name}` | {shown} | {default_text(kind, value)} | {doc} |")
        out.append("")
    return "\n".join(out)


def block_of(path):
    text = open(path, encoding="utf-8").read()
    if BEGIN not in text or END not in text:
        sys.exit(f"param_table: {path} has no {BEGIN} ... {END} block")
    a, b = text.index(BEGIN) + len(BEGIN), text.index(END)
    return text, a, b


def main(argv):
    table = markdown()
    if len(argv) == 1:
        print(table)
        return 0
    if len(argv) != 3 or argv[1] not in ("--write", "--check"):
        print(__doc__, file=sys.stderr)
        return 2
    text, a, b = block_of(argv[2])
    wanted = "\n" + table + "\n"
    if argv[1] == "--check":
        if text[a:b] != wanted:
            print(f"param_table: the parameter table in {argv[2]} is not the one "
                  f"dacpo_param_table.h gives; run scripts/param_table.py --write {argv[2]}",
                  file=sys.stderr)
            return 1
        return 0
    with open(argv[2] + ".tmp", "w", encoding="utf-8") as fh:
        fh.write(text[:a] + wanted + text[b:])
    os.replace(argv[2] + ".tmp", argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
