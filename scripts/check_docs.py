#!/usr/bin/env python3
"""Checks that the docs match the tree (ctest DocsMatchTheTree):

1. every folder README names every source file of its folder (its file name, `stem.*`, or the
   stem in backticks), so a newcomer finds each file from the folder's page;
2. every citation of a section of docs/design.md (the file name, then the heading in double quotes
   or after a comma, also across a comment's line break) names a heading that exists;
3. the include direction: nothing in engine/ includes a render/ or compute/ file or the public
   <canopy/canopy.h> (engine/ takes the types both sides share from <canopy/canopy_core.h>);
4. the public header speaks of the method and its parameters, not of issue numbers or seed files.

Usage: check_docs.py [REPO_ROOT] [--pretend-file PATH ...]   (exit 0: all hold; 1: each problem on
a line). --pretend-file adds a file that does not exist to the listing: the check's own test shows
that a README missing a file fails it.
"""
import os
import re
import sys

DESIGN = "design" + ".md"  # spelled apart so this file cites nothing itself
SOURCE_ENDINGS = (".h", ".cpp", ".comp", ".vert", ".frag", ".glsl", ".sh", ".py", ".cmake", ".in")
# engine/ files allowed to include the public header, each with the reason (none: engine/ takes
# Status, Result, the math types, ResourceState and the device types from <canopy/canopy_core.h>).
KNOWN_PUBLIC_HEADER_USERS = {}


def tracked_files(root):
    out = []
    for base, dirs, files in os.walk(root):
        rel = os.path.relpath(base, root)
        parts = [] if rel == "." else rel.split(os.sep)
        if parts and (parts[0] in ("build", "demo_out", "layers_out", "sim_out", "out") or parts[0].startswith(".")):
            dirs[:] = []
            continue
        for f in files:
            out.append(os.path.normpath(os.path.join(rel, f)) if rel != "." else f)
    return out


def check_readmes(root, files, problems):
    folders = sorted({os.path.dirname(f) for f in files if os.path.basename(f) == "README.md" and os.path.dirname(f)})
    for folder in folders:
        if folder.startswith("docs") or folder.startswith("third_party_notes"):
            continue
        text = open(os.path.join(root, folder, "README.md"), encoding="utf-8").read()
        for f in sorted(files):
            if os.path.dirname(f) != folder or not f.endswith(SOURCE_ENDINGS):
                continue
            name = os.path.basename(f)
            stem = name.split(".")[0]
            named = (re.search(r"(?<![\w.])" + re.escape(name) + r"(?!\w)", text)
                     or (stem + ".*") in text
                     or ("`" + stem + "`") in text)
            if not named:
                problems.append(f"{folder}/README.md does not name {name}")


def headings(root):
    hs = set()
    for line in open(os.path.join(root, "docs", DESIGN), encoding="utf-8"):
        m = re.match(r"#{2,4} (.+?)\s*$", line)
        if m:
            hs.add(m.group(1))
    return hs


# A quoted heading right after design.md, allowing "'s", commas, brackets, "section" and a comment
# leader on the next line between them.
QUOTED = re.compile(r"design\.md(?:'s)?[\s,(]*(?:(?://|#|\*)\s*)?(?:section\s+)?\"([^\"\n]+)\"")
UNQUOTED = re.compile(r"design\.md,\s+([A-Z][A-Za-z][A-Za-z :-]*?)[).;]")


def check_citations(root, files, problems):
    hs = headings(root)
    for f in files:
        if not (f.endswith(SOURCE_ENDINGS) or f.endswith(".md") or f.endswith("CMakeLists.txt")):
            continue
        try:
            text = open(os.path.join(root, f), encoding="utf-8").read()
        except (UnicodeDecodeError, FileNotFoundError):
            continue
        for rx in (QUOTED, UNQUOTED):
            for m in rx.finditer(text):
                title = m.group(1).strip()
                if title not in hs:
                    line = text.count("\n", 0, m.start()) + 1
                    problems.append(f"{f}:{line}: cites docs/design.md \"{title}\", which has no such heading")


def check_includes(root, files, problems):
    inc = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
    for f in files:
        if not f.startswith("engine/") or not f.endswith((".h", ".cpp")) or not os.path.exists(os.path.join(root, f)):
            continue
        text = open(os.path.join(root, f), encoding="utf-8").read()
        for m in inc.finditer(text):
            target = m.group(1)
            if target.startswith(("render/", "compute/")):
                problems.append(f"{f} includes {target}: engine/ must not depend on render/ or compute/")
            if target == "canopy/canopy.h" and f not in KNOWN_PUBLIC_HEADER_USERS:
                problems.append(f"{f} includes <canopy/canopy.h>: engine/ must not depend on the public header")


def check_public_header(root, problems):
    for name in sorted(os.listdir(os.path.join(root, "render", "include", "canopy"))):
        path = os.path.join("render", "include", "canopy", name)
        for n, line in enumerate(open(os.path.join(root, path), encoding="utf-8"), 1):
            if re.search(r"\bissues?\s+#?\d+", line, re.I) or re.search(r"\bseeds?\s+\d{3}\b|\b\d{3}_\w+\.(md|pdf|txt)", line):
                problems.append(f"{path}:{n}: cites an issue number or a seed file: {line.strip()}")


def main():
    args = sys.argv[1:]
    pretend = []
    while "--pretend-file" in args:
        i = args.index("--pretend-file")
        pretend.append(os.path.normpath(args[i + 1]))
        del args[i:i + 2]
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), ".."))
    files = tracked_files(root) + pretend
    problems = []
    check_readmes(root, files, problems)
    check_citations(root, files, problems)
    check_includes(root, files, problems)
    check_public_header(root, problems)
    for p in problems:
        print(p)
    checked = len([f for f in files if f.endswith(SOURCE_ENDINGS)])
    print(f"docs check: {len(problems)} problems ({checked} source files, {len(headings(root))} design.md headings)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
