#!/usr/bin/env python3
"""Lines of every Rust function outside tests, longest first.

Usage: tools/fn_lengths.py [N] [paths...]   (default: the 10 longest under crates/ and src/)

A function is counted from its `fn` line to the line of its closing brace; bodies inside
`#[cfg(test)]` modules and files under tests/, benches/ and examples/ are skipped.
"""
import os, re, sys

def strip(line):
    """The line without comments, string and char literals (their braces are not code)."""
    line = re.sub(r'"([^"\\]|\\.)*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "''", line)
    return line.split("//")[0]

def functions(path):
    lines = open(path, encoding="utf-8").read().split("\n")
    out, in_test, test_depth, depth = [], False, 0, 0
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("#[cfg(test)]"):
            in_test, test_depth = True, depth
        m = re.match(r"\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)", line)
        if m and not in_test:
            # find the opening brace, then its match
            d, j, opened = 0, i, False
            while j < len(lines):
                code = strip(lines[j])
                for ch in code:
                    if ch == "{":
                        d += 1; opened = True
                    elif ch == "}":
                        d -= 1
                if opened and d == 0:
                    break
                if not opened and code.rstrip().endswith(";"):
                    break
                j += 1
            if opened:
                out.append((j - i + 1, f"{path}:{i + 1}", m.group(6)))
        code = strip(line)
        depth += code.count("{") - code.count("}")
        if in_test and depth <= test_depth and "}" in code:
            in_test = False
        i += 1
    return out

def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    roots = sys.argv[2:] or ["crates", "src"]
    found = []
    for root in roots:
        for d, _, files in os.walk(root):
            if any(p in d.split(os.sep) for p in ("tests", "benches", "examples", "target")):
                continue
            for f in files:
                if f.endswith(".rs"):
                    found += functions(os.path.join(d, f))
    found.sort(reverse=True)
    for length, where, name in found[:n]:
        print(f"{length:5} {name:32} {where}")
    print(f"{sum(1 for f in found if f[0] > 150)} functions longer than 150 lines")

main()
