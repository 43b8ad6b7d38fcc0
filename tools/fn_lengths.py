#!/usr/bin/env python3
"""Lists the longest Rust functions outside tests, longest first.

    tools/fn_lengths.py [--top N] PATH...   (files or directories)

A function's length is its lines from the `fn` line to its closing brace,
inclusive; items inside `#[cfg(test)]` modules and files under `tests/` are
skipped. Comments and string literals are blanked before braces are counted.
"""
import re
import sys
from pathlib import Path


def blank(src: str) -> str:
    """Comments, strings and char literals replaced by spaces (newlines kept)."""
    out, i, n = [], 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif src.startswith("/*", i):
            depth, j = 0, i
            while j < n:
                if src.startswith("/*", j): depth += 1; j += 2
                elif src.startswith("*/", j):
                    depth -= 1; j += 2
                    if depth == 0: break
                else: j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j])); i = j
        elif re.match(r'r#*"', src[i:i + 20]) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            m = re.match(r'r(#*)"', src[i:])
            end = src.find('"' + m.group(1), i + len(m.group(0)))
            j = n if end < 0 else end + 1 + len(m.group(1))
            out.append(re.sub(r"[^\n]", " ", src[i:j])); i = j
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j])); i = j
        elif c == "'":
            m = re.match(r"'(\\[^']{1,10}|[^'\\])'", src[i:])
            if m:
                out.append(" " * len(m.group(0))); i += len(m.group(0))
            else:
                out.append(c); i += 1
        else:
            out.append(c); i += 1
    return "".join(out)


def close(code: str, open_at: int) -> int:
    depth = 0
    for j in range(open_at, len(code)):
        if code[j] == "{": depth += 1
        elif code[j] == "}":
            depth -= 1
            if depth == 0: return j
    return len(code) - 1


def functions(path: Path):
    code = blank(path.read_text())
    # Test modules out.
    skip = []
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{", code):
        skip.append((m.start(), close(code, m.end() - 1)))
    mod = path.with_suffix("").as_posix()
    for m in re.finditer(r"\bfn\s+(\w+)", code):
        if any(a <= m.start() <= b for a, b in skip):
            continue
        # The body: the first `{` after the signature, unless a `;` ends it (a trait item).
        k = m.end()
        depth = 0
        while k < len(code):
            ch = code[k]
            if code.startswith("->", k): k += 2; continue
            if ch in "(<[": depth += 1
            elif ch in ")>]": depth -= 1
            elif ch == ";" and depth <= 0: k = -1; break
            elif ch == "{" and depth <= 0: break
            k += 1
        if k < 0 or k >= len(code):
            continue
        end = close(code, k)
        first = code.count("\n", 0, m.start()) + 1
        last = code.count("\n", 0, end) + 1
        yield last - first + 1, f"{mod}::{m.group(1)}", first


def main(argv):
    top = 10
    if argv[:1] == ["--top"]:
        top, argv = int(argv[1]), argv[2:]
    files = []
    for a in argv:
        p = Path(a)
        files += sorted(p.rglob("*.rs")) if p.is_dir() else [p]
    rows = [r for f in files if "tests" not in f.parts for r in functions(f)]
    rows.sort(key=lambda r: -r[0])
    for n, name, line in rows[:top]:
        print(f"{n:5}  {name} (line {line})")


if __name__ == "__main__":
    main(sys.argv[1:])
