#!/usr/bin/env python3
"""docs/cli.md and the binary agree: each subcommand's `--help` is quoted in its section of the
doc, line for line from `Usage:` on, and every `--option` the section's prose names is an option
of that subcommand (or of the subcommand the sentence names: `sidc compile --form`).

Usage: check_help_docs.py SIDC_BINARY DOCS/CLI.MD
Exit 0 when they agree; 1 with each difference on stderr (the subcommand, the line, what to do).
"""
import re
import subprocess
import sys

SUBCOMMANDS = ["compile", "fit", "simulate", "select", "export"]


def help_text(sidc, sub):
    out = subprocess.run([sidc, sub, "--help"], capture_output=True, text=True, check=True).stdout
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Usage:"))
    return [line.rstrip() for line in lines[start:] if line.strip()]


def options_of(help_lines):
    return set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*|-[a-z])\b", "\n".join(help_lines))) | {"--help", "-h"}


def sections(doc):
    found = {}
    parts = re.split(r"^## ", doc, flags=re.M)
    for part in parts:
        m = re.match(r"`sidc (\w+)`", part)
        if m:
            found[m.group(1)] = part
    return found


def main():
    sidc, doc_path = sys.argv[1], sys.argv[2]
    doc = open(doc_path, encoding="utf-8").read()
    by_name = sections(doc)
    helps = {sub: help_text(sidc, sub) for sub in SUBCOMMANDS}
    problems = []
    for sub in SUBCOMMANDS:
        if sub not in by_name:
            problems.append(f"docs/cli.md has no section `## \\`sidc {sub}\\``: add one quoting `sidc {sub} --help`")
            continue
        section = by_name[sub]
        blocks = re.findall(r"^```\n(.*?)^```", section, flags=re.M | re.S)
        quoted = next((b for b in blocks if f"Usage: sidc {sub}" in b), None)
        if quoted is None:
            problems.append(f"sidc {sub}: its section quotes no `Usage: sidc {sub}` block: paste `sidc {sub} --help` there")
            continue
        doc_lines = [line.rstrip() for line in quoted.splitlines()]
        doc_lines = [line for line in doc_lines[next(i for i, l in enumerate(doc_lines) if l.startswith("Usage:")):] if line.strip()]
        if doc_lines != helps[sub]:
            for i in range(max(len(doc_lines), len(helps[sub]))):
                d = doc_lines[i] if i < len(doc_lines) else "(nothing)"
                h = helps[sub][i] if i < len(helps[sub]) else "(nothing)"
                if d != h:
                    problems.append(f"sidc {sub} --help differs from docs/cli.md at line {i + 1} of the block:\n  doc:    {d}\n  binary: {h}")
                    break
        # The prose: every option named is one of this subcommand's, or of the subcommand named
        # just before it in the same sentence-ish stretch (`sidc select ... --simulate`).
        own = options_of(helps[sub])
        prose = re.sub(r"^```.*?^```", "", section, flags=re.M | re.S)
        for m in re.finditer(r"(?<![\w-])(--[a-z][a-z0-9-]*)", prose):
            option = m.group(1)
            if option in own:
                continue
            before = prose[max(0, m.start() - 120):m.start()]
            named = re.findall(r"sidc (\w+)", before)
            if named and named[-1] in helps and option in options_of(helps[named[-1]]):
                continue
            line = section[:section.find(prose[m.start():m.start() + 40])].count("\n") + 1 if prose[m.start():m.start() + 40] in section else 0
            problems.append(f"sidc {sub}: docs/cli.md names `{option}` (section line {line}), which `sidc {sub} --help` does not list")
    for p in problems:
        print(p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
