#!/usr/bin/env python3
"""Keeps files and functions small enough to read (issue #20, "split by concept"): no source
file over 1000 lines and no function over 120, in every C/C++ file git tracks. A function is a
top-level body: a line that is exactly "{" after a line that is not a declaration ends with
";" or "=", up to the next line that is exactly "}" (the .clang-format style puts both braces
alone at column 0); type definitions do not count. Criterion's Test(...) bodies count as functions. Prints each offender and
exits 1; else one line of counts."""
import os
import subprocess
import sys

MAX_FILE, MAX_FUNCTION = 1000, 120
# a body after one of these is a type or a block of declarations, not a function
TYPES = ("typedef ", "struct ", "enum ", "union ", "extern ", "class ", "namespace ")
os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
files = subprocess.check_output(["git", "ls-files", "*.c", "*.h", "*.cc"], text=True).split()
files = [f for f in files if os.path.isfile(f)]
bad = []
functions = 0
for path in files:
    lines = open(path, encoding="utf-8").read().split("\n")
    if len(lines) - 1 > MAX_FILE:
        bad.append(f"{path}: {len(lines) - 1} lines (at most {MAX_FILE})")
    start = None
    for i, line in enumerate(lines):
        head = lines[i - 1] if i > 0 else ""
        if line == "{" and not head.rstrip().endswith(("=", ";")) and not head.startswith(TYPES):
            start = i
        elif line.startswith("}") and start is not None:
            functions += 1
            length = i - start + 2  # with the signature's line and the closing brace
            if length > MAX_FUNCTION:
                name = lines[start - 1].strip()[:70]
                bad.append(f"{path}:{start}: {length} lines (at most {MAX_FUNCTION}): {name}")
            start = None
for line in bad:
    print("size-check: " + line, file=sys.stderr)
if not bad:
    print(f"size-check: {len(files)} files within {MAX_FILE} lines, {functions} functions within {MAX_FUNCTION}")
sys.exit(1 if bad else 0)
