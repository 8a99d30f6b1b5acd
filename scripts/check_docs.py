#!/usr/bin/env python3
"""Checks that the docs match the tree (ctest DocsMatchTheTree):

1. every folder README names every source file of its folder (its file name, `stem.*`, or the
   stem in backticks), so a newcomer finds each file from the folder's page;
2. every citation of a section of docs/design.md, performance.md, lab/performance-notebook.md,
   embedding.md, tuning.md, reliability.md or getting-started.md (the file name, then the heading
   in double quotes or after a comma, also across a comment's line break) names a heading that
   exists;
3. the include direction: nothing in engine/ includes a render/ or compute/ file or the public
   <canopy/canopy.h> (engine/ takes the types both sides share from <canopy/canopy_core.h>);
4. the public header speaks of the method and its parameters, not of issue numbers or seed files;
5. every repository path named in README.md, CONTRIBUTING.md, docs/**/*.md and the folder READMEs
   exists (a glob or `name.*` matches at least one file);
6. every Canopy program named there exists, and every option written after it on a command line
   is in that program's --help (with --bin BUILD_DIR; `scripts/run.sh` stands for canopy-demo);
7. every find_package(Canopy X.Y) names the header's CANOPY_VERSION_MAJOR.MINOR;
8. every row of a table in docs/parameters.md has as many cells as its header row;
9. every C++ block of README.md and docs/ is a compiled sample or says it is a fragment
   (scripts/doc_samples.py);
10. every default quoted for a parameter (`Struct.field` followed within its clause by "default N"
   or "(N, the default)") is the schema's default in docs/parameters.md (the lab notebook, which
   keeps the defaults of their day, and parameters.md itself are not read).

Usage: check_docs.py [REPO_ROOT] [--bin BUILD_DIR] [--pretend-file PATH ...] [--plant KIND]
(exit 0: all hold; 1: each problem on a line). --pretend-file adds a file that does not exist to
the listing: the check's own test shows that a README missing a file fails it. --plant adds one
planted error to the docs as read (path, option, version, table or sample), so the planted-error
tests show that each check fails on what it is meant to catch.
"""
import glob
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import doc_samples  # noqa: E402

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


def headings(root, page=os.path.join("docs", DESIGN)):
    """A page's headings, each also without its "N. " number (`## 9. Versions` is cited "Versions")
    and up to its first comma."""
    hs = set()
    for line in open(os.path.join(root, page), encoding="utf-8"):
        m = re.match(r"#{2,4} (.+?)\s*$", line)
        if m:
            hs.add(m.group(1))
            hs.add(re.sub(r"^\d+\.\s+", "", m.group(1)))
            hs.add(m.group(1).split(", ")[0])  # "What a reprojected frame costs, and ..." cited short
    return hs


# The docs pages whose sections are cited by name: "docs/PAGE.md "Heading"" (or ", Heading").
CITED = {name: os.path.join("docs", *folder, name) + ".md" for name, folder in (
    ("design", ()), ("performance", ()), ("performance-notebook", ("lab",)), ("embedding", ()),
    ("tuning", ()), ("reliability", ()), ("getting-started", ()))}
CITED["CONTRIBUTING"] = "CONTRIBUTING.md"
# A quoted heading right after the page's name, allowing "'s", commas, brackets, "section" and a
# comment leader on the next line between them.
PAGE = r"(?<![\w-])(" + "|".join(re.escape(k) for k in CITED) + r")\.md"
QUOTED = re.compile(PAGE + r"(?:'s)?[\s,(]*(?:(?://|#|\*)\s*)?(?:section\s+)?\"(?=[A-Za-z0-9])([^\"\n]+(?:\n[ \t]*(?:(?://|#|\*)[ \t]*)?[^\"\n]+)?)\"")
UNQUOTED = re.compile(PAGE + r",\s+([A-Z][A-Za-z][A-Za-z :-]*?)[).;]")


def check_citations(root, files, problems):
    hs = {k: headings(root, p) for k, p in CITED.items() if os.path.exists(os.path.join(root, p))}
    for f in files:
        if not (f.endswith(SOURCE_ENDINGS) or f.endswith(".md") or f.endswith("CMakeLists.txt")):
            continue
        try:
            text = open(os.path.join(root, f), encoding="utf-8").read()
        except (UnicodeDecodeError, FileNotFoundError):
            continue
        for rx in (QUOTED, UNQUOTED):
            for m in rx.finditer(text):
                page = m.group(1)
                title = re.sub(r"\s*\n\s*(?:(?://|#|\*)\s*)?", " ", m.group(2)).strip()  # across a line break
                if page in hs and title not in hs[page]:
                    line = text.count("\n", 0, m.start()) + 1
                    problems.append(f"{f}:{line}: cites {CITED[page]} \"{title}\", which has no such heading")


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


TOP = ("engine", "compute", "render", "shaders", "tests", "tools", "demo", "bench", "scripts", "docs",
       "third_party_notes", "cmake", ".ci")
ROOT_FILES = ("README.md", "CHANGELOG.md", "CONTRIBUTING.md", "LICENSE", "CMakeLists.txt")
PATH = re.compile(r"(?<![\w./~-])((?:" + "|".join(re.escape(t) for t in TOP) + r")/[\w.*{},/-]*)")
PROGRAMS = ("canopy-demo", "canopy-bench", "canopy-scene", "canopy-sim", "canopy-layers", "canopy-example-host",
            "canopy-game-host", "canopy-smoke")
PLANTS = {
    "path": "See `render/planted_missing_file.h` for the details.",
    "option": "Run `./build/release/canopy-demo --planted-missing-option 3`.",
    "version": "In the host's CMakeLists: `find_package(Canopy 0.1 REQUIRED)`.",
    "sample": "```cpp\nint planted_unmarked_block = 1;\n```",
    "default": "The warp's filter keeps leaves sharp (`CompositeParams.sharpness`, default 7).",
}


def doc_pages(root):
    """README.md, CONTRIBUTING.md, docs/**/*.md and every folder README (not third-party notes)."""
    pages = [f for f in ("README.md", "CONTRIBUTING.md") if os.path.exists(os.path.join(root, f))]
    for base, dirs, files in os.walk(os.path.join(root, "docs")):
        dirs.sort()
        pages += [os.path.relpath(os.path.join(base, f), root) for f in sorted(files) if f.endswith(".md")]
    for top in TOP:
        if top != "docs" and os.path.exists(os.path.join(root, top, "README.md")):
            pages.append(os.path.join(top, "README.md"))
    return pages


def read_pages(root, plant):
    texts = {p: open(os.path.join(root, p), encoding="utf-8").read() for p in doc_pages(root)}
    if plant in PLANTS:
        texts["README.md"] += "\n" + PLANTS[plant] + "\n"
    return texts


def path_exists(root, path):
    path = path.rstrip(".,;:")
    if "{" in path:  # render/x.{h,cpp}: each alternative
        m = re.match(r"(.*)\{([^}]*)\}(.*)", path)
        return m and all(path_exists(root, m.group(1) + alt + m.group(3)) for alt in m.group(2).split(","))
    if os.path.exists(os.path.join(root, path)):
        return True
    if glob.glob(os.path.join(root, path)):
        return True
    if "." not in os.path.basename(path) and glob.glob(os.path.join(root, path) + "*"):
        return True  # a prefix the command completes (plot_bench.py's docs/perf -> docs/perf_*.png)
    # shaders/composite*.comp/vert/frag: a file name with its other extensions after slashes.
    parts = path.split("/")
    for i, part in enumerate(parts):
        if "." in part and i + 1 < len(parts):
            head = "/".join(parts[:i + 1])
            return bool(glob.glob(os.path.join(root, head)))
    return False


def check_paths(root, texts, problems):
    for page, text in texts.items():
        for n, line in enumerate(text.split("\n"), 1):
            for m in PATH.finditer(line):
                path = m.group(1)
                if path.rstrip("/") in TOP or re.search(r"\b[A-Z]{3,}\b", path):
                    continue  # a top folder itself, or a placeholder (shaders/NAME.comp)
                if not path_exists(root, path):
                    problems.append(f"{page}:{n}: names {path}, which is not in the repository")


def command_lines(text):
    """Lines with backslash continuations joined."""
    out, cur, start = [], "", 1
    for n, line in enumerate(text.split("\n"), 1):
        if not cur:
            start = n
        if line.rstrip().endswith("\\"):
            cur += line.rstrip()[:-1] + " "
            continue
        out.append((start, cur + line))
        cur = ""
    return out


def check_programs(root, texts, bin_dir, problems):
    helps = {}
    for prog in PROGRAMS:
        exe = os.path.join(bin_dir, prog)
        if not os.path.exists(exe):
            problems.append(f"{prog} is not built in {bin_dir}: cannot check its options")
            continue
        r = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60)
        helps[prog] = r.stdout + r.stderr
    call = re.compile(r"(?<![\w-])(canopy-[a-z-]+[a-z]|scripts/run\.sh)\b")
    for page, text in texts.items():
        for n, line in command_lines(text):
            for m in call.finditer(line):
                prog = "canopy-demo" if m.group(1) == "scripts/run.sh" else m.group(1)
                if re.search(r"\.py\s[^;|&`]*$", line[:m.start()]):
                    continue  # the program is an argument of a script (bench_ab.py OLD/canopy-bench ...)
                if prog not in PROGRAMS:
                    if not re.match(r"canopy-(bench|demo)-", prog):
                        problems.append(f"{page}:{n}: names a program {prog}, which Canopy does not build")
                    continue
                if prog not in helps:
                    continue
                # The options of this command: up to the end of the command or of the code span.
                rest = re.split(r"`|;|\||&&|\s#\s|\)|\s(?=canopy-|scripts/)", line[m.end():])[0]
                for opt in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", rest):
                    if opt == "--help":
                        continue
                    if not re.search(r"(?<![\w-])" + re.escape(opt) + r"(?![\w-])", helps[prog]):
                        problems.append(f"{page}:{n}: {prog} {opt}: no such option in `{prog} --help`")


def check_versions(root, texts, problems):
    core = open(os.path.join(root, "render", "include", "canopy", "canopy_core.h"), encoding="utf-8").read()
    major = re.search(r"#define CANOPY_VERSION_MAJOR (\d+)", core).group(1)
    minor = re.search(r"#define CANOPY_VERSION_MINOR (\d+)", core).group(1)
    want = f"{major}.{minor}"
    sources = dict(texts)
    consumer = os.path.join("tests", "consumer", "CMakeLists.txt")
    if os.path.exists(os.path.join(root, consumer)):
        sources[consumer] = open(os.path.join(root, consumer), encoding="utf-8").read()
    for page, text in sources.items():
        for m in re.finditer(r"find_package\(Canopy\s+(\d+(?:\.\d+)*)", text):
            got = ".".join(m.group(1).split(".")[:2])
            if got != want:
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"{page}:{line}: find_package(Canopy {m.group(1)}) but the header is {want}")


def table_cells(row):
    return len(re.findall(r"(?<!\\)\|", row.strip())) - 1


def check_parameter_table(root, plant, problems):
    page = os.path.join("docs", "parameters.md")
    text = open(os.path.join(root, page), encoding="utf-8").read()
    if plant == "table":
        text = text.replace("|---|---|---|---|---|---|\n", "|---|---|---|---|---|---|\n| `planted` | `a|b` | `0` | — |  | a planted row |\n", 1)
    header = None
    for n, line in enumerate(text.split("\n"), 1):
        if not line.startswith("|"):
            header = None
            continue
        cells = table_cells(line)
        if header is None:
            header = cells
        elif cells != header:
            problems.append(f"{page}:{n}: {cells} cells where the table has {header} (an unescaped '|'?)")


def schema_defaults(root):
    """{"Struct.field": default as a float} from docs/parameters.md's tables (numbers only)."""
    out, struct = {}, None
    path = os.path.join(root, "docs", "parameters.md")
    if not os.path.exists(path):
        return out
    for line in open(path, encoding="utf-8"):
        m = re.match(r"## (\w+)", line)
        if m:
            struct = m.group(1)
            continue
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]] if line.startswith("| `") else []
        if struct and len(cells) >= 3:
            value = cells[2].strip("` ").rstrip("fu")
            try:
                out[f"{struct}.{cells[0].strip('` ')}"] = float(value)
            except ValueError:
                pass
    return out


DEFAULT_QUOTE = re.compile(r"`(\w+\.\w+)`[^.;`\n]{0,60}?\bdefault(?:s to| is|:)?\s+`?(-?\d+(?:\.\d+)?)")


def check_defaults(root, texts, problems):
    defaults = schema_defaults(root)
    quoted = 0
    for page, text in texts.items():
        if page.startswith(os.path.join("docs", "lab")) or page == os.path.join("docs", "parameters.md"):
            continue
        for m in DEFAULT_QUOTE.finditer(text.replace("\n", " ")):
            name, value = m.group(1), float(m.group(2))
            if name not in defaults:
                continue
            quoted += 1
            if abs(defaults[name] - value) > 1e-9 * max(1.0, abs(value)):
                problems.append(f"{page}: {name} quoted with default {m.group(2)}; the schema's is {defaults[name]:g} "
                                "(docs/parameters.md)")
    return quoted


def check_samples(root, texts, problems):
    for page, text in texts.items():
        if page != "README.md" and not page.startswith("docs"):
            continue
        for line, name, first, _ in doc_samples.blocks_of_text(text):
            if not name and not first.lstrip().startswith("// Fragment"):
                problems.append(f"{page}:{line}: a C++ block neither marked <!-- sample: NAME --> nor starting '// Fragment'")


def main():
    args = sys.argv[1:]
    pretend = []
    while "--pretend-file" in args:
        i = args.index("--pretend-file")
        pretend.append(os.path.normpath(args[i + 1]))
        del args[i:i + 2]
    bin_dir = plant = None
    if "--bin" in args:
        i = args.index("--bin")
        bin_dir = args[i + 1]
        del args[i:i + 2]
    if "--plant" in args:
        i = args.index("--plant")
        plant = args[i + 1]
        del args[i:i + 2]
        if plant not in PLANTS and plant != "table":
            sys.exit(f"check_docs: --plant takes one of {', '.join(list(PLANTS) + ['table'])}")
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), ".."))
    files = tracked_files(root) + pretend
    problems = []
    check_readmes(root, files, problems)
    check_citations(root, files, problems)
    check_includes(root, files, problems)
    check_public_header(root, problems)
    texts = read_pages(root, plant)
    check_paths(root, texts, problems)
    if bin_dir:
        check_programs(root, texts, bin_dir, problems)
    else:
        print("docs check: programs and options not checked (no --bin BUILD_DIR)")
    check_versions(root, texts, problems)
    check_parameter_table(root, plant, problems)
    check_samples(root, texts, problems)
    quoted = check_defaults(root, texts, problems)
    for p in problems:
        print(p)
    checked = len([f for f in files if f.endswith(SOURCE_ENDINGS)])
    print(f"docs check: {len(problems)} problems ({checked} source files, {len(headings(root))} design.md headings, "
          f"{quoted} quoted parameter defaults)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
