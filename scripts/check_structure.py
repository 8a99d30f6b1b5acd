#!/usr/bin/python3
"""The structure limits of CONTRIBUTING.md "Conventions in the code", its limits, checked (issue 68; ctest StructureLimits):

  a source file (C++, GLSL, Python, shell) over 900 lines
  a C++ function over 150 lines (from its signature's first line to its closing brace)
  render/canopy.cpp over 650 lines
  docs/performance.md over 300 lines
  README.md over 220 lines

Usage: scripts/check_structure.py [REPO]   (default: the folder above this script)
       scripts/check_structure.py --self-test  (made-up files: a 160-line function, a 901-line file,
                                                a macro's braces, a lambda inside a function)
Prints each excess and exits 1 when there is one. Plain Python, no dependencies.
The function finder is a brace counter with comments, strings and character literals skipped: a
'{' at namespace or class level whose text since the previous ';', '{' or '}' holds a parameter
list (and no '=') opens a function; lambdas and blocks inside it count towards it."""
import os
import re
import subprocess
import sys

FILE_LIMIT = 900
FUNCTION_LIMIT = 150
SPECIAL = {"render/canopy.cpp": 650, os.path.join("docs", "performance" + ".md"): 300, "README.md": 220}
SOURCE = re.compile(r"\.(cpp|cc|h|hpp|comp|glsl|frag|vert|py|sh)$")
CPP = re.compile(r"\.(cpp|cc|h|hpp)$")
SCOPE = re.compile(r"\b(namespace|struct|class|union|enum)\b")
CONTROL = re.compile(r"^\s*(if|for|while|switch|catch|do|else)\b")


def strip(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i):  # raw string R"delim( ... )delim"
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(" " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(code):
    """Preprocessor lines (with their continuations) blanked: a macro's braces are not code."""
    lines = code.split("\n")
    cont = False
    for k, line in enumerate(lines):
        if cont or line.lstrip().startswith("#"):
            cont = line.rstrip().endswith("\\")
            lines[k] = " " * len(line)
    return "\n".join(lines)


def functions(text):
    """(name, first line, last line) of each function body at namespace or class level."""
    code = blank_preprocessor(strip(text))
    stack = []  # per open brace: 'scope' (namespace/class/extern/initializer) or a function record
    found = []
    last = 0  # index after the previous ';', '{' or '}'
    for i, c in enumerate(code):
        if c == "{":
            prefix = code[last:i]
            inside = any(isinstance(s, tuple) for s in stack)
            if inside:
                stack.append("block")
            elif SCOPE.search(prefix) and "(" not in prefix.split("{")[-1].split(":")[0]:
                stack.append("scope")
            elif "(" in prefix and ")" in prefix and "=" not in prefix.replace("==", "").replace("operator=", "") \
                    and not CONTROL.match(prefix) and prefix.strip() and not prefix.strip().startswith("extern"):
                start = i - len(prefix) + (len(prefix) - len(prefix.lstrip()))
                line = code.count("\n", 0, start) + 1
                name = re.findall(r"([~\w:]+(?:operator\S*)?)\s*\(", prefix)
                stack.append((name[0] if name else "?", line))
            else:
                stack.append("scope")
            last = i + 1
        elif c == "}":
            if stack:
                top = stack.pop()
                if isinstance(top, tuple):
                    found.append((top[0], top[1], code.count("\n", 0, i) + 1))
            last = i + 1
        elif c == ";":
            last = i + 1
    return found


def tracked(repo):
    try:
        out = subprocess.run(["git", "-C", repo, "ls-files"], capture_output=True, text=True, check=True).stdout
        return [f for f in out.splitlines() if os.path.isfile(os.path.join(repo, f))]
    except (OSError, subprocess.CalledProcessError):
        files = []
        for root, dirs, names in os.walk(repo):
            dirs[:] = [d for d in dirs if not d.startswith(".") and d != "build"]
            files += [os.path.relpath(os.path.join(root, n), repo) for n in names]
        return files


def self_test():
    """The finder on made-up sources: what must be caught is, what must not be is not."""
    long_fn = "int f(int x) {\n" + "  x += 1;\n" * 158 + "  return x;\n}\n"
    found = functions(long_fn)
    assert found == [("f", 1, 161)], found
    nested = "namespace a {\nstruct S {\n  void m() {\n    auto l = [](int) { return 1; };\n  }\n};\n}  // namespace a\n"
    assert functions(nested) == [("m", 3, 5)], functions(nested)
    macro = "#define X(a) \\\n  { a; }\nvoid g() {}\n"
    assert functions(macro) == [("g", 3, 3)], functions(macro)
    text = "'{' // {\n/* { */ const char* s = \"{\";\nvoid h() {\n}\n"
    assert functions(text) == [("h", 3, 4)], functions(text)
    print("structure: self-test passed (a 161-line function found, lambdas, macros, strings and comments not counted)")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    problems = []
    checked_files = checked_functions = 0
    for rel in sorted(tracked(repo)):
        if rel.startswith(("build/", "third_party")) or "/fuzz/regressions/" in rel:
            continue
        path = os.path.join(repo, rel)
        limit = SPECIAL.get(rel, FILE_LIMIT if SOURCE.search(rel) else None)
        if limit is None:
            continue
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        checked_files += 1
        if lines > limit:
            problems.append(f"{rel}: {lines} lines (limit {limit})")
        if CPP.search(rel):
            for name, first, end in functions(text):
                checked_functions += 1
                if end - first + 1 > FUNCTION_LIMIT:
                    problems.append(f"{rel}:{first}: function {name} is {end - first + 1} lines (limit {FUNCTION_LIMIT})")
    for p in problems:
        print(f"structure: {p}")
    print(f"structure: {checked_files} files, {checked_functions} C++ functions checked, {len(problems)} over the limits")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
