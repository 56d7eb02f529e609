#!/usr/bin/env python3
"""The layout rules of docs/architecture.md, checked on the sources.

  1. include/shtool/ (what an engine includes) reaches neither nlohmann/json nor FFTW,
     directly or through another shtool header;
  2. src/runtime/ and include/shtool/ include nothing of src/offline/ or src/cli/;
  3. src/offline/ includes nothing of src/cli/, and no job includes another job's header:
     a `*_job.h` is included only by its own `.cpp` (the CLI includes any); what two jobs
     share lives in a library header of their folders;
  4. no source or doc names a file the repository does not hold, a path out of it,
     or a tracker's issue.

Usage: check_layout.py SOURCE_DIR   (exit 1 and one line per violation)
"""
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
# src/runtime has a lighting/ folder of its own, so the offline lighting/ cannot be told apart by prefix.
OFFLINE_ROOTS = ("common/", "fit/", "lobes/", "tensors/", "interop/", "shaders/", "render/", "deform/", "wrinkles/",
                 "scene/", "probes/")
FORBIDDEN_IN_ENGINE = ("nlohmann/", "fftw3")


def includes(path):
    return INCLUDE.findall(path.read_text(encoding="utf-8", errors="replace"))


def main():
    root = pathlib.Path(sys.argv[1])
    problems = []
    headers = {p.name: p for p in (root / "include/shtool").glob("*.h")}

    # 1. transitive closure inside include/shtool
    for name, path in sorted(headers.items()):
        seen, todo = set(), [path]
        while todo:
            p = todo.pop()
            if p in seen:
                continue
            seen.add(p)
            for inc in includes(p):
                if any(inc.startswith(f) for f in FORBIDDEN_IN_ENGINE):
                    chain = "" if p == path else f" (through {p.name})"
                    problems.append(f"include/shtool/{name} reaches <{inc}>{chain}")
                if inc.startswith("shtool/") and inc[len("shtool/"):] in headers:
                    todo.append(headers[inc[len("shtool/"):]])

    # 2. and 3.
    def check_tree(tree, forbidden, what):
        for p in sorted((root / tree).rglob("*")):
            if p.suffix not in (".h", ".cpp"):
                continue
            for inc in includes(p):
                if any(inc.startswith(f) for f in forbidden):
                    problems.append(f"{p.relative_to(root)} includes \"{inc}\" ({what})")

    check_tree("include/shtool", OFFLINE_ROOTS + ("cli_common",), "the engine API must not depend on the offline tool")
    check_tree("src/runtime", OFFLINE_ROOTS + ("cli_common",), "the runtime must not depend on the offline tool")
    check_tree("src/offline", ("cli_common",), "the offline libraries must not depend on the CLI")

    # 3b. one job, one header: src/offline/<folder>/<name>_job.h only from <name>_job.cpp
    job_header = re.compile(r"^[a-z_]+/([a-z_]+_job)\.h$")
    for p in sorted((root / "src/offline").rglob("*")):
        if p.suffix not in (".h", ".cpp"):
            continue
        for inc in includes(p):
            m = job_header.match(inc)
            if m and p.name != m.group(1) + ".cpp":
                problems.append(f"{p.relative_to(root)} includes \"{inc}\" (another job's header: move what they "
                                "share into a library header)")

    # 4. references that a reader of the repository cannot follow: a document (.md,
    # .pdf) named but not held by the repository, a content-addressed text file (a name
    # with a long hexadecimal run), a relative path that climbs out of the repository, or
    # an issue of a tracker. Scratch files the tests create (a.txt) are not documents.
    def in_repository(p):
        top = p.relative_to(root).parts[0]
        return top != ".git" and not top.startswith("build")
    held = {p.name for p in root.rglob("*") if p.is_file() and in_repository(p)}
    named_file = re.compile(r"([A-Za-z0-9_./-]+\.(?:md|pdf))\b")
    hashed_text = re.compile(r"[0-9a-f]{12,}\.txt\b")
    climbing = re.compile(r"(?<![A-Za-z0-9_.])\.\./[A-Za-z]")
    tracker = re.compile(r"\bissues? #?[0-9]+\b", re.I)
    for tree in ("include", "src", "docs", "bench", "scripts", "tests", "schemas", "README.md", "CMakeLists.txt"):
        base = root / tree
        files = [base] if base.is_file() else sorted(base.rglob("*"))
        for p in files:
            if not p.is_file() or p.suffix not in (".h", ".cpp", ".md", ".py", ".sh", ".txt", ".cmake", ".json", ""):
                continue
            if "corpus" in p.parts:
                continue
            for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
                where = f"{p.relative_to(root)}:{n}"
                for name in named_file.findall(line):
                    if pathlib.PurePosixPath(name).name not in held:
                        problems.append(f"{where}: names '{name}', which the repository does not hold")
                if hashed_text.search(line):
                    problems.append(f"{where}: names a text file outside the repository")
                if climbing.search(line):
                    problems.append(f"{where}: a relative path that leaves the repository")
                if tracker.search(line):
                    problems.append(f"{where}: refers to a tracker's issue")

    for line in problems:
        print(line)
    if problems:
        print(f"{len(problems)} layout rule violation(s)", file=sys.stderr)
        return 1
    print("layout rules hold")
    return 0


if __name__ == "__main__":
    sys.exit(main())
