#!/usr/bin/env python3
"""docs/EQUATIONS.md stays true: every row that names a file and a function must name a file
that exists, a function defined in it, and a file that carries the row's tag ("Jeong Eq. 13";
a range such as "Jeong Eq. 11-12" covers 11 and 12). Every equation tag in the kernels' code
must have its row. Prints what is wrong and exits 1; else one line of counts."""
import os
import re
import sys

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
os.chdir(root)
table = open("docs/EQUATIONS.md", encoding="utf-8").read()
# the "what" column may hold escaped bars (\|) of absolute values
row = re.compile(r"^\|\s*(Jeong|Tang|Lu)\s*\|\s*(\d+)\s*\|(?:[^|\\]|\\\|)*\|\s*`([^`]+)`\s*\|\s*`([^`]+)`\s*\|", re.M)
tag = re.compile(r"\b(Jeong|Tang|Lu) Eqs?\. ?(\d+)(?:\s*[–-]\s*(\d+))?")


def tags_in(text):
    found = set()
    for m in tag.finditer(text):
        lo = int(m.group(2))
        hi = int(m.group(3)) if m.group(3) else lo
        for n in range(lo, hi + 1):
            found.add((m.group(1), n))
    return found


bad = []
rows = set()
for paper, number, path, function in row.findall(table):
    key = (paper, int(number))
    rows.add(key)
    if not os.path.isfile(path):
        bad.append(f"{paper} Eq. {number}: {path} does not exist")
        continue
    text = open(path, encoding="utf-8").read()
    if not re.search(r"^[A-Za-z_][^;(]*\b" + re.escape(function) + r"\s*\(", text, re.M):
        bad.append(f"{paper} Eq. {number}: {path} defines no function {function}")
    if key not in tags_in(text):
        bad.append(f"{paper} Eq. {number}: {path} carries no tag '{paper} Eq. {number}'")

code = set()
for dirpath, _, files in os.walk("kernels"):
    if "/ref" in dirpath:
        continue
    for f in files:
        if f.endswith(".c"):
            code |= tags_in(open(os.path.join(dirpath, f), encoding="utf-8").read())
for paper, number in sorted(code - rows):
    bad.append(f"{paper} Eq. {number} is tagged in kernels/ but has no row in docs/EQUATIONS.md")

for line in bad:
    print("equations-check: " + line, file=sys.stderr)
if not bad:
    print(f"equations-check: {len(rows)} equations, each at its file and function")
sys.exit(1 if bad else 0)
