# SPDX-License-Identifier: BSD-3-Clause
"""The parameter lists written by hand agree with the C defaults: the type
stub names every keyword orient() takes, the docstring's ``name=value``
defaults are the C ones, and the README's parameter table gives the C default
wherever it gives a plain value."""
import ast
import os
import re

import pcl_dacpo

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(HERE, "..", "pcl_dacpo")
ROOT = os.path.join(HERE, "..", "..", "..")
ALIASES = {"num_threads": "threads"}  # the stub's alias of threads


def stub_keywords():
    tree = ast.parse(open(os.path.join(SRC, "__init__.pyi")).read())
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "orient")
    return {a.arg for a in fn.args.kwonlyargs} - {"progress"}


def test_the_stub_names_every_keyword():
    defaults = set(pcl_dacpo.default_params())
    stub = {ALIASES.get(k, k) for k in stub_keywords()}
    assert defaults - stub == set(), "missing from __init__.pyi"
    assert stub - defaults == set(), "in __init__.pyi but not a parameter"


def test_the_docstring_gives_the_c_defaults():
    d = pcl_dacpo.default_params()
    doc = pcl_dacpo.orient.__doc__
    pairs = re.findall(r"``(\w+)=([^`(]+?)``", doc)
    assert len(pairs) >= 5
    for name, value in pairs:
        if name not in d or name == "viewpoint":
            continue
        value = value.strip("'\"")
        try:
            assert float(value) == float(d[name]), f"{name}: doc {value}, C {d[name]}"
        except ValueError:
            assert value == str(d[name]), f"{name}: doc {value}, C {d[name]}"


def test_the_readme_table_gives_the_c_defaults():
    """README.md has the user rows, docs/PARAMETERS.md the method switches."""
    docs = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "docs", "PARAMETERS.md")]
    d = pcl_dacpo.default_params()
    checked = 0
    lines = [line for path in docs for line in open(path, encoding="utf-8")]
    for line in lines:
        m = re.match(r"^\| `(\w+)` \| [^|]* \| ([^|]+) \|", line)
        if not m or m.group(1) not in d:
            continue
        shown = m.group(2).strip().replace("−", "-").split(" ")[0]
        c = d[m.group(1)]
        if isinstance(c, bool):
            c = int(c)
        try:
            assert float(shown) == float(c), f"{m.group(1)}: README {shown}, C {c}"
        except ValueError:
            assert shown == str(c), f"{m.group(1)}: README {shown}, C {c}"
        checked += 1
    assert checked >= 25
