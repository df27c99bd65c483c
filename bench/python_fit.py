#!/usr/bin/env python3
"""python_fit: a fit from numpy arrays in the Python module against `sidc fit` on the same record.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_fit.py --sidc build/cli/sidc [--rows 1e7] [--runs 3] [--keep]
    PYTHONPATH=build/python /usr/bin/python3 bench/python_fit.py --only-arrays [--rows 1e7]

The model is bench/fit_bench.cpp's: 20 candidate operations of a second-order system in derivative
form (savgol(7, 3), y'' by the arc applied twice), six of them true. The record is made in numpy
without integrating anything: y(t) a sum of sines, y' and y'' exact, x the true left-hand side, so
the true six coefficients are known. It is written to DIR/record.csv with 17 significant digits,
which read back to the very same doubles: both paths fit identical numbers, and the script checks
that their estimates agree to 1e-12.

Timed (wall clock, median of --runs, each path alternately):
  cli    `sidc fit model.sid --data record.csv --no-validate` as a child process: compile, read the
         CSV, bind, fit, report (what a shell user waits for);
  arrays m.fit({"t": t, "x": x, "y": y}, no_validate=True) on arrays already in memory: the
         conversion into the record, bind, fit, the report text;
  csv    m.fit("record.csv", no_validate=True): the CLI's work inside Python.
--only-arrays makes the arrays and fits them once, nothing else (no CSV, no CLI): a whole process
for farm-bench, whose peak memory is the record's arrays plus what the fit adds to them.
Relies on: numpy and the module (python/), the sidc binary. Writes only into --dir.
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

import sidc

MODEL = """# bench/python_fit.py: bench/fit_bench.cpp's model
model fit_bench
input  x
output y
param  m, c[1..6], s[1..6], d[1..7]
data "record.csv" (t = "t", x = "x", y = "y")
set derivative = savgol(7, 3)
set integrate = 0
m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x
"""
# m*y'' + 0.3 y' + 0.05 y'^3 + y + 0.5 y^3 + 0.2 y^2 y' = x (fit_bench's system)
TRUTH = {"m": 1.0, "c[1]": 0.3, "c[3]": 0.05, "s[1]": 1.0, "s[3]": 0.5, "d[2]": 0.2}


def record(rows):
    """t, x and y, filled a million rows at a time: no whole-record temporaries, so that a process's
    peak memory is the three arrays plus what the fit adds to them."""
    t, x, y = np.empty(rows), np.empty(rows), np.empty(rows)
    for first in range(0, rows, 1_000_000):
        part = slice(first, min(rows, first + 1_000_000))
        tp = np.arange(part.start, part.stop) * 0.001
        yp = 0.8 * np.sin(0.7 * tp) + 0.3 * np.sin(1.9 * tp + 0.3) + 0.1 * np.sin(3.7 * tp)
        dy = 0.56 * np.cos(0.7 * tp) + 0.57 * np.cos(1.9 * tp + 0.3) + 0.37 * np.cos(3.7 * tp)
        ddy = -0.392 * np.sin(0.7 * tp) - 1.083 * np.sin(1.9 * tp + 0.3) - 1.369 * np.sin(3.7 * tp)
        t[part], y[part] = tp, yp
        x[part] = ddy + 0.3 * dy + 0.05 * dy**3 + yp + 0.5 * yp**3 + 0.2 * yp**2 * dy
    return {"t": t, "x": x, "y": y}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sidc", help="the sidc binary (all but --only-arrays)")
    parser.add_argument("--only-arrays", action="store_true", help="one fit from numpy arrays, nothing else")
    parser.add_argument("--rows", type=float, default=1e7)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--dir", default="/tmp/sidc-python-bench")
    parser.add_argument("--keep", action="store_true", help="reuse DIR/record.csv when it has --rows rows")
    a = parser.parse_args()
    rows = int(a.rows)
    if a.only_arrays:
        data = record(rows)
        arrays = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        result = sidc.compile(MODEL.replace('data "record.csv" (t = "t", x = "x", y = "y")\n', "")).fit(data, no_validate=True)
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"{rows} rows from arrays: peak {arrays:.0f} MiB with the arrays made, {peak:.0f} MiB after the fit; largest error "
              f"against the true coefficients {max(abs(result.estimates[k] - TRUTH.get(k, 0.0)) for k in result.estimates):.1e}")
        return
    if not a.sidc:
        parser.error("--sidc is required (but for --only-arrays)")
    os.makedirs(a.dir, exist_ok=True)
    model_path = os.path.join(a.dir, "model.sid")
    csv = os.path.join(a.dir, "record.csv")
    with open(model_path, "w") as f:
        f.write(MODEL)
    data = record(rows)
    stamp = os.path.join(a.dir, "record.rows")
    if not (a.keep and os.path.exists(stamp) and open(stamp).read() == str(rows)):
        started = time.perf_counter()
        np.savetxt(csv, np.column_stack([data["t"], data["x"], data["y"]]), fmt="%.17g", delimiter=",", header="t,x,y", comments="")
        with open(stamp, "w") as f:
            f.write(str(rows))
        print(f"wrote {csv} ({os.path.getsize(csv) / 1e6:.0f} MB) in {time.perf_counter() - started:.1f} s")

    model = sidc.compile(model_path)
    times = {"cli": [], "arrays": [], "csv": []}
    estimates = {}
    for run in range(a.runs):
        started = time.perf_counter()
        done = subprocess.run([a.sidc, "fit", model_path, "--data", csv, "--no-validate"], capture_output=True, text=True)
        times["cli"].append(time.perf_counter() - started)
        if done.returncode != 0:
            sys.exit(f"sidc fit failed:\n{done.stderr}")
        started = time.perf_counter()
        result = model.fit(data, no_validate=True)
        times["arrays"].append(time.perf_counter() - started)
        estimates["arrays"] = result.estimates
        started = time.perf_counter()
        result = model.fit(csv, no_validate=True)
        times["csv"].append(time.perf_counter() - started)
        estimates["csv"] = result.estimates
        print(f"run {run + 1}: " + ", ".join(f"{k} {v[-1]:.3f} s" for k, v in times.items()), flush=True)

    worst = max(abs(estimates["arrays"][k] - estimates["csv"][k]) / max(1.0, abs(estimates["csv"][k])) for k in estimates["csv"])
    truth = max(abs(estimates["arrays"][k] - TRUTH.get(k, 0.0)) for k in estimates["arrays"])
    print(f"\n{rows} rows, {a.runs} runs, wall seconds (median, min-max):")
    for k, v in times.items():
        print(f"  {k:7s} {statistics.median(v):7.3f}  ({min(v):.3f}-{max(v):.3f})")
    print(f"estimates from arrays and from the CSV differ by at most {worst:.1e} (relative); "
          f"largest error against the true coefficients {truth:.1e}")
    if worst > 1e-12:
        sys.exit("the two paths disagree")


if __name__ == "__main__":
    main()
