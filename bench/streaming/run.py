#!/usr/bin/env python3
"""Issue 16's table: each path of `sidc` on a long record, wall time and peak resident memory.

The record is fit_bench's (bench/fit_bench.cpp: a forced Duffing-van der Pol oscillator, RK4, 39 bytes
a row), generated once per size and kept in --dir; the models are its 20 candidate operations in the
derivative form, integrated once, in the weak form, and `sidc select` over them; optionally the fit
with the whole record validated (--validate-samples 0). Each command runs --runs times, one after
another; its wall time (a monotonic clock around the child) and peak resident memory (the child's
own ru_maxrss from wait4) are printed as median (min-max). With --as-limit BYTES, the derivative fit
of the largest record is run once more under `prlimit --as=BYTES` and its outcome printed.

Python standard library only. Usage (bench/README.md, "Streaming"):
    python3 bench/streaming/run.py --sidc build/cli/sidc --fit-bench build/bench/fit_bench [--rows 1e6,1e7]
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

MODEL = """# bench/streaming: fit_bench's 20 candidate operations ({form})
model streaming_bench
input  x
output y
param  m, c[1..6], s[1..6], d[1..7]
data "{csv}" (t = "t", x = "x", y = "y")
set derivative = savgol(7, 3)
{setting}
m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x
"""

FORMS = {
    "derivative": "set integrate = 0",
    "integrated": "set integrate = 1",
    "weak": "set form = weak",
}


def run_once(command, cwd):
    """Wall seconds, peak MiB and exit status of one run; stdout and stderr kept apart."""
    with open(os.path.join(cwd, "last.out"), "wb") as out, open(os.path.join(cwd, "last.err"), "wb") as err:
        start = time.monotonic()
        child = subprocess.Popen(command, cwd=cwd, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.monotonic() - start
    child.returncode = os.waitstatus_to_exitcode(status)
    return wall, usage.ru_maxrss / 1024.0, child.returncode


def measure(command, cwd, runs):
    walls, peaks = [], []
    for _ in range(runs):
        wall, peak, code = run_once(command, cwd)
        if code != 0:
            with open(os.path.join(cwd, "last.err"), errors="replace") as err:
                tail = err.read()[-400:]
            return None, f"exit {code}: {tail.strip()}"
        walls.append(wall)
        peaks.append(peak)
    return (statistics.median(walls), min(walls), max(walls), statistics.median(peaks)), None


def rows_argument(text):
    return [int(float(v)) for v in text.split(",") if v]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sidc", required=True, help="the sidc binary")
    parser.add_argument("--fit-bench", default="build/bench/fit_bench",
                        help="fit_bench (cmake -DSIDC_BUILD_BENCH=ON), which writes the record")
    parser.add_argument("--rows", type=rows_argument, default=[10**6, 10**7], help="record sizes, e.g. 1e6,1e7,1e8")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--dir", default="/tmp/sidc-streaming-bench")
    parser.add_argument("--validate", action="store_true", help="also the fit with the whole record validated")
    parser.add_argument("--as-limit", type=int, default=0, metavar="BYTES",
                        help="run the largest record's derivative fit under prlimit --as=BYTES")
    args = parser.parse_args()
    sidc = os.path.abspath(args.sidc)
    os.makedirs(args.dir, exist_ok=True)

    print(f"bench/streaming: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}, {args.runs} runs each")
    print("| rows | path | wall s, median (min-max) | peak MiB | / fit derivative |")
    print("| ---: | --- | ---: | ---: | ---: |")
    for rows in args.rows:
        csv = f"fit-{rows}.csv"
        if not os.path.exists(os.path.join(args.dir, csv)):
            subprocess.run([args.fit_bench, "--rows", str(rows), "--keep", "--skip-library", "--skip-cli", "--dir", args.dir],
                           check=True, stdout=subprocess.DEVNULL)
        for form, setting in FORMS.items():
            with open(os.path.join(args.dir, f"{form}-{rows}.sid"), "w") as f:
                f.write(MODEL.format(form=form, csv=csv, setting=setting))
        paths = [
            ("fit, derivative form", ["fit", f"derivative-{rows}.sid", "--no-validate"]),
            ("fit, integrated once", ["fit", f"integrated-{rows}.sid", "--no-validate"]),
            ("fit, weak form", ["fit", f"weak-{rows}.sid", "--no-validate"]),
            ("select (exact, 20 candidates)", ["select", f"derivative-{rows}.sid"]),
        ]
        if args.validate:
            paths.append(("fit, whole record validated", ["fit", f"derivative-{rows}.sid", "--validate-samples", "0"]))
        reference = None
        for name, command in paths:
            result, failure = measure([sidc] + command, args.dir, args.runs)
            if failure:
                print(f"| {rows:.0e} | {name} | failed: {failure} | | |")
                continue
            median, low, high, peak = result
            reference = reference or median
            print(f"| {rows:.0e} | {name} | {median:.2f} ({low:.2f}-{high:.2f}) | {peak:.0f} | {median / reference:.2f} |")
        sys.stdout.flush()
    if args.as_limit:
        rows = max(args.rows)
        command = ["prlimit", f"--as={args.as_limit}", sidc, "fit", f"derivative-{rows}.sid", "--no-validate"]
        wall, peak, code = run_once(command, args.dir)
        with open(os.path.join(args.dir, "last.err"), errors="replace") as err:
            tail = err.read()[-300:].strip()
        verdict = "fitted" if code == 0 else f"exit {code}: {tail}"
        print(f"\nunder prlimit --as={args.as_limit}: {rows:.0e} rows, derivative fit: {verdict} ({wall:.2f} s, peak {peak:.0f} MiB)")


if __name__ == "__main__":
    main()
