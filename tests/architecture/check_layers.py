#!/usr/bin/env python3
"""The layers' include rules (docs/architecture.md, ../../CMakeLists.txt), checked on the sources.

    check_layers.py SOURCE_DIR               scan SOURCE_DIR; exit 1 naming file:line of every
                                             forbidden #include, 0 when there is none
    check_layers.py --self-test SOURCE_DIR   prove the scan can fail: copy the sources to a temporary
                                             folder, plant one forbidden include per rule, and expect
                                             each to be reported at its file and line

Data flows one way: diagnostics/ and ir/ at the bottom, grammar/ -> compiler/ -> runtime/ ->
report/ -> driver/ -> cli/, with distributed/ (on runtime/) beside driver/. A folder may include its own headers and those of the layers it lists below;
everything outside the layers (tests/, bench/, examples/) may include any layer but cli/.
Includes are read as the project writes them, by paths relative to the repository root
(`#include "runtime/solve/fit.hpp"`). Every path is normalised first (`a/../b`); a quoted path
is resolved against the including file's folder when a file of that name is there (`"../ir/ir.hpp"`,
`"solve/../../compiler/x.hpp"`), else against the repository root. The folder the normalised path
starts with is the layer it names. Every folder of the repository is scanned except build trees
and hidden ones: one that is not a layer counts as outside the layers.
"""
import os
import re
import shutil
import sys
import tempfile

# What each layer may include besides itself. cli/ may include every layer.
LAYERS = ["diagnostics", "ir", "grammar", "compiler", "runtime", "report", "driver", "distributed", "cli"]
ALLOWED = {
    "diagnostics": set(),
    "ir": {"diagnostics"},
    "grammar": {"diagnostics"},
    "compiler": {"grammar", "ir", "diagnostics"},
    "runtime": {"ir", "diagnostics"},
    "report": {"runtime", "ir", "diagnostics"},
    "driver": {"report", "runtime", "compiler", "grammar", "ir", "diagnostics"},
    # distributed/: the processes of one command (MPI); it implements runtime/'s RowShare.
    "distributed": {"runtime", "ir", "diagnostics"},
    "cli": {"driver", "distributed", "report", "runtime", "compiler", "grammar", "ir", "diagnostics"},
}
SOURCE_SUFFIXES = (".hpp", ".cpp", ".h", ".hh", ".cc", ".cxx", ".hxx", ".ipp", ".inl", ".tpp")
INCLUDE = re.compile(r'^\s*#\s*include\s*(["<])([^">]+)[">]')


def included_layer(root, including_file, quote, path):
    """The layer folder an include names, or None when it is not one of sidc's."""
    beside = os.path.normpath(os.path.join(os.path.dirname(including_file), path))
    if quote == '"' and (path.startswith(".") or os.path.exists(beside)):  # relative to the includer
        path = os.path.relpath(beside, root)
    else:
        path = os.path.normpath(path)
    path = path.replace(os.sep, "/")
    first = path.split("/", 1)[0]
    return first if "/" in path and first in LAYERS else None


def source_files(root):
    """(top folder, path) of every source file, build trees and hidden folders left out."""
    for folder, dirs, files in os.walk(root):
        relative = os.path.relpath(folder, root)
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and not d.startswith("build")
                         and not (relative == "." and d == "Testing"))
        top = relative.split(os.sep, 1)[0] if relative != "." else ""
        for name in sorted(files):
            if name.endswith(SOURCE_SUFFIXES):
                yield top, os.path.join(folder, name)


def violations(root):
    """(file relative to root, line number, message) for every forbidden include, and the count of
    files scanned."""
    found, scanned = [], 0
    for top, path in source_files(root):
        scanned += 1
        with open(path, encoding="utf-8", errors="replace") as f:
            for number, line in enumerate(f, 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                layer = included_layer(root, path, m.group(1), m.group(2))
                if layer is None or layer == top:
                    continue
                allowed = ALLOWED[top] if top in ALLOWED else set(LAYERS) - {"cli"}
                if layer not in allowed:
                    where = top + "/" if top in ALLOWED else "code outside the layers (" + (top or ".") + "/)"
                    found.append((os.path.relpath(path, root), number,
                                  f"{where} may not include {layer}/: {line.strip()}"))
    return found, scanned


def scan(root):
    found, scanned = violations(root)
    for path, number, message in found:
        print(f"{path}:{number}: error: {message}")
    if found:
        print(f"{len(found)} forbidden include(s) in {scanned} files; the layers and what each may "
              f"include: tests/architecture/check_layers.py")
        return 1
    print(f"layers: {scanned} files, no forbidden include")
    return 0


# One planted include per rule of the brief, into a file of the layer (line 1 of a new file, or
# appended to an existing one), each of which must be reported at its file and line.
PLANTS = [
    ("runtime/solve/fit.cpp", "compiler/pipeline.hpp"),
    ("runtime/records/planted.hpp", "grammar/parse.hpp"),
    ("runtime/select/planted.cpp", "report/atomic_file.hpp"),
    ("report/planted.cpp", "compiler/pipeline.hpp"),
    ("report/planted.hpp", "grammar/ast.hpp"),
    ("diagnostics/planted.cpp", "ir/ir.hpp"),
    ("ir/planted.cpp", "grammar/ast.hpp"),
    ("ir/planted.hpp", "runtime/solve/fit.hpp"),
    ("grammar/planted.cpp", "ir/ir.hpp"),
    ("grammar/planted.hpp", "compiler/pipeline.hpp"),
    ("compiler/planted.cpp", "runtime/solve/fit.hpp"),
    ("compiler/planted.hpp", "report/atomic_file.hpp"),
    ("compiler/planted_cli.cpp", "cli/read_file.hpp"),
    ("tests/runtime/planted_test.cpp", "cli/record_options.hpp"),
    ("runtime/operators/planted_relative.cpp", "../../compiler/pipeline.hpp"),
    ("runtime/solve/planted_dotdot.cpp", "runtime/../compiler/pipeline.hpp"),
    ("runtime/solve/planted_beside.cpp", "../../compiler/../compiler/pipeline.hpp"),
    ("plugins/planted.cpp", "cli/exit_codes.hpp"),
    ("report/planted.inl", "grammar/ast.hpp"),
    ("report/planted_driver.cpp", "driver/fit_run.hpp"),
    ("driver/planted.cpp", "cli/exit_codes.hpp"),
]
# Includes that are allowed, planted too: none may be reported.
ALLOWED_PLANTS = [
    ("cli/planted.cpp", "compiler/pipeline.hpp"),
    ("report/planted_ok.cpp", "runtime/solve/fit.hpp"),
    ("driver/planted_ok.cpp", "compiler/pipeline.hpp"),
    ("compiler/planted_ok.cpp", "grammar/parse.hpp"),
    ("tests/runtime/planted_ok.cpp", "compiler/pipeline.hpp"),
    ("runtime/solve/planted_ok.cpp", "../records/bind_record.hpp"),
]


def plant(copy, relative, include):
    path = os.path.join(copy, relative)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    lines = 0
    if os.path.exists(path):
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        if text and not text.endswith("\n"):
            with open(path, "a", encoding="utf-8") as f:
                f.write("\n")
    with open(path, "a", encoding="utf-8") as f:
        f.write(f'#include "{include}"  // planted by check_layers.py --self-test\n')
    return lines + 1


def self_test(root):
    problems = []
    with tempfile.TemporaryDirectory(prefix="sidc-layers-") as copy:
        for _, path in source_files(root):
            target = os.path.join(copy, os.path.relpath(path, root))
            os.makedirs(os.path.dirname(target), exist_ok=True)
            shutil.copyfile(path, target)
        found, _ = violations(copy)
        if found:
            problems.append(f"the unchanged copy already has {len(found)} forbidden include(s)")
        expected = {(os.path.normpath(r), plant(copy, r, i)) for r, i in PLANTS}
        for r, i in ALLOWED_PLANTS:
            plant(copy, r, i)
        found, _ = violations(copy)
        reported = {(os.path.normpath(p), n) for p, n, _ in found}
        for path, number in sorted(expected - reported):
            problems.append(f"planted forbidden include not reported: {path}:{number}")
        for path, number in sorted(reported - expected):
            problems.append(f"reported, but not a planted forbidden include: {path}:{number}")
        with open(os.devnull, "w") as quiet:
            stdout, sys.stdout = sys.stdout, quiet
            try:
                status = scan(copy)
            finally:
                sys.stdout = stdout
        if status != 1:
            problems.append(f"the scan of the planted copy exited {status}, not 1")
    for p in problems:
        print("error: " + p)
    if problems:
        return 1
    print(f"layers self-test: all {len(PLANTS)} planted forbidden includes reported at their lines, "
          f"none of the {len(ALLOWED_PLANTS)} allowed ones")
    return 0


def main(argv):
    if len(argv) == 2 and argv[0] == "--self-test":
        return self_test(os.path.abspath(argv[1]))
    if len(argv) == 1:
        return scan(os.path.abspath(argv[0]))
    print(__doc__.strip(), file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
