#!/usr/bin/env python3
"""Issue 17's measurement: `sidc fit` as one process and as N MPI ranks on the same long record.

The record and the 20-term models are bench/streaming's (fit_bench's forced Duffing-van der Pol
oscillator, generated once into --dir). For each form (derivative, weak; --no-validate, so that the
fit itself is timed) the commands run in rounds, one of each per round in turn (A/B pairs on a
shared machine): `sidc fit` alone, and `mpirun -np N sidc fit` for each N of --ranks (oversubscribed
where N exceeds the cores). Wall time is a monotonic clock around the child; peak memory is the
largest resident set among the job's processes (wait4's ru_maxrss covers the child and its reaped
descendants). Medians with min-max are printed, and each report is compared with the single
process's apart from the lines naming processes and threads: where printed digits differ (estimates
at rounding level, true zeros of the benchmark's library), the largest difference of an estimate
relative to the largest estimate is printed (issue 17 asks for 1e-12).

Python standard library only. Usage (bench/README.md, "Distributed"):
    python3 bench/distributed/run.py --sidc build/cli/sidc --fit-bench build/bench/fit_bench [--rows 1e7] [--ranks 1,2,4]
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "streaming"))
from run import FORMS, MODEL, run_once as timed_run  # noqa: E402  (bench/streaming/run.py: the same models and timer)


def run_once(command, cwd):
    """streaming/run.py's timed run (wall, peak MiB, exit code), and the report it printed."""
    wall, peak, code = timed_run(command, cwd)
    with open(os.path.join(cwd, "last.out"), errors="replace") as f:
        return wall, peak, code, f.read()


PARAMETER = re.compile(r"^  (\S+)\s+([-+0-9.eE]+)\s+([-+0-9.eE]+)\s+\[")


def estimates(report):
    """Each parameter's printed estimate, by name (the fit report's table)."""
    return {m.group(1): float(m.group(2)) for m in map(PARAMETER.match, report.splitlines()) if m}


def difference(reference, report):
    """None when the reports agree line by line (but for the lines naming processes and threads);
    else (largest difference, what it is): of a printed estimate relative to the largest estimate,
    or, for a report without a parameter table, of any printed number relative to itself."""
    def keep(r):
        times = re.compile(r"\b[0-9.]+(e-?[0-9]+)? s\b")  # select's search times
        return [times.sub("", x) for x in r.splitlines() if not x.startswith("processes: ") and "streamed QR over" not in x]
    if keep(reference) == keep(report):
        return None
    a, b = estimates(reference), estimates(report)
    if a and a.keys() == b.keys():
        scale = max(abs(v) for v in a.values()) or 1.0
        return max(abs(a[k] - b[k]) for k in a) / scale, "estimate difference, of the largest estimate"
    # No parameter table (select): the same words, and each differing number's relative difference.
    worst = 0.0
    for x, y in zip(keep(reference), keep(report)):
        tx, ty = x.split(), y.split()
        if len(tx) != len(ty):
            return float("inf"), "a line of another shape"
        for u, v in zip(tx, ty):
            if u == v:
                continue
            try:
                fu, fv = float(u), float(v)
            except ValueError:
                return float("inf"), f"`{u}` against `{v}`"
            worst = max(worst, abs(fu - fv) / max(abs(fu), abs(fv)))
    return worst, "relative difference of a printed number (rounding-level columns of a noise-free record)"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sidc", required=True)
    parser.add_argument("--fit-bench", required=True)
    parser.add_argument("--mpirun", default=shutil.which("mpirun") or "mpirun")
    parser.add_argument("--rows", default="1e7")
    parser.add_argument("--ranks", default="1,2,4")
    parser.add_argument("--forms", default="derivative,weak,select",
                        help="fit forms (derivative, integrated, weak) and `select` (sidc select over the derivative form's candidates)")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--dir", default="/tmp/sidc-bench-distributed")
    a = parser.parse_args()
    rows = int(float(a.rows))
    ranks = [int(r) for r in a.ranks.split(",")]
    os.makedirs(a.dir, exist_ok=True)
    csv = f"fit-{rows}.csv"
    if not os.path.exists(os.path.join(a.dir, csv)):
        print(f"generating {csv} ...", flush=True)
        subprocess.run([os.path.abspath(a.fit_bench), "--rows", str(rows), "--keep", "--skip-library", "--skip-cli", "--dir", a.dir],
                       check=True, stdout=subprocess.DEVNULL)
    env_note = "OMPI_ALLOW_RUN_AS_ROOT" if os.geteuid() == 0 else None
    if env_note:  # mpirun refuses root unless told; the bench runs as root on CI-like machines
        os.environ.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    sidc = os.path.abspath(a.sidc)
    print(f"record {csv}: {rows} rows; {os.cpu_count()} cores; {a.runs} rounds; medians (min-max)")
    print(f"{'form':<11} {'processes':<26} {'wall s':>22} {'peak MiB (largest process)':>28}")
    for form in a.forms.split(","):
        model = "derivative" if form == "select" else form
        with open(os.path.join(a.dir, f"{model}.sid"), "w") as f:
            f.write(MODEL.format(form=model, csv=csv, setting=FORMS[model]))
        job = [sidc, "select", f"{model}.sid"] if form == "select" else [sidc, "fit", f"{model}.sid", "--no-validate"]
        commands = [(f"sidc {job[1]} (one process)", job)]
        # --bind-to none: mpirun would pin each of one or two ranks to one core, and a rank's
        # threads (the node's cores divided among its ranks) would share it.
        for n in ranks:
            commands.append((f"mpirun -np {n}", [a.mpirun, "--oversubscribe", "--bind-to", "none", "-np", str(n), *job]))
        walls = {name: [] for name, _ in commands}
        peaks = {name: [] for name, _ in commands}
        reference, failures, differences = None, [], {}
        for _ in range(a.runs):
            for name, command in commands:
                wall, peak, code, report = run_once(command, a.dir)
                if code != 0:
                    failures.append(f"{name}: exit {code}")
                    continue
                if reference is None:
                    reference = report
                else:
                    d = difference(reference, report)
                    if d is not None and d[0] >= differences.get(name, (-1.0, ""))[0]:
                        differences[name] = d
                walls[name].append(wall)
                peaks[name].append(peak)
        for name, _ in commands:
            w, p = walls[name], peaks[name]
            if not w:
                print(f"{form:<11} {name:<26} {'failed':>22}")
                continue
            print(f"{form:<11} {name:<26} {statistics.median(w):>8.2f} ({min(w):.2f}-{max(w):.2f})"
                  f" {statistics.median(p):>12.0f} ({min(p):.0f}-{max(p):.0f})")
        for name, (d, what) in differences.items():
            verdict = "" if what.startswith("relative") else ("  <-- TOO LARGE" if d > 1e-12 else " (rounding)")
            print(f"  {name}: the report differs from one process's in printed digits; largest {what}: {d:.1e}{verdict}")
        for f in sorted(set(failures)):
            print(f"  FAILED: {f}")


if __name__ == "__main__":
    main()
