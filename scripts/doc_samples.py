#!/usr/bin/env python3
"""The C++ code blocks of README.md and docs/**/*.md, extracted so that the build compiles them.

Every ```cpp block in those files is one of two kinds, and says which:
  - a compiled sample: the line before its fence is `<!-- sample: NAME -->`. The blocks of one
    NAME are concatenated in the order they appear (a sample may be told in several steps with text
    between them) into NAME.cpp, which tests/CMakeLists.txt compiles against the public headers
    (a sample with `int main(` is linked and run by ctest, the others compiled);
  - a fragment: its first line is a comment starting with `// Fragment` (it shows a piece of a
    host and is not compiled).
A block that is neither is an error (scripts/check_docs.py reports it), so a new block cannot
silently escape compilation.

Usage: doc_samples.py ROOT --write DIR   (writes DIR/NAME.cpp when its text changed, prints one line
                                          per sample: NAME main|object)
       doc_samples.py ROOT --check       (exit 1 listing each unmarked block)
"""
import os
import re
import sys

FENCE = re.compile(r"^```(cpp|c\+\+|C\+\+)\s*$")
MARK = re.compile(r"^<!--\s*sample:\s*([A-Za-z0-9_]+)\s*-->\s*$")


def doc_files(root):
    out = [os.path.join(root, "README.md")]
    for base, dirs, files in os.walk(os.path.join(root, "docs")):
        dirs.sort()
        out += [os.path.join(base, f) for f in sorted(files) if f.endswith(".md")]
    return [f for f in out if os.path.exists(f)]


def blocks(path):
    """(line number, sample name or None, first code line, code) for every C++ block of a file."""
    return blocks_of_text(open(path, encoding="utf-8").read())


def blocks_of_text(text):
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        if FENCE.match(lines[i]):
            start = i
            j = i + 1
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            code = lines[i + 1:j]
            k = start - 1
            while k >= 0 and not lines[k].strip():
                k -= 1
            m = MARK.match(lines[k]) if k >= 0 else None
            yield start + 1, (m.group(1) if m else None), (code[0] if code else ""), "\n".join(code) + "\n"
            i = j + 1
        else:
            i += 1


def collect(root):
    samples, problems = {}, []
    for path in doc_files(root):
        rel = os.path.relpath(path, root)
        for line, name, first, code in blocks(path):
            if name:
                samples.setdefault(name, []).append(f"#line {line + 1} \"{rel}\"\n" + code)
            elif not first.lstrip().startswith("// Fragment"):
                problems.append(f"{rel}:{line}: a C++ block neither marked <!-- sample: NAME --> nor starting "
                                f"'// Fragment'")
    return samples, problems


def main():
    args = sys.argv[1:]
    if len(args) < 2 or args[1] not in ("--write", "--check"):
        print(__doc__, file=sys.stderr)
        return 2
    root = os.path.abspath(args[0])
    samples, problems = collect(root)
    if args[1] == "--check":
        for p in problems:
            print(p)
        return 1 if problems else 0
    out = args[2]
    os.makedirs(out, exist_ok=True)
    for name, parts in sorted(samples.items()):
        text = "// Extracted from the docs by scripts/doc_samples.py: edit the docs, not this file.\n" + "".join(parts)
        path = os.path.join(out, name + ".cpp")
        old = open(path, encoding="utf-8").read() if os.path.exists(path) else None
        if old != text:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        print(name, "main" if re.search(r"\bint\s+main\s*\(", text) else "object")
    for p in problems:  # reported, not fatal here: ctest DocSamplesAllMarked fails on them
        print(p, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
