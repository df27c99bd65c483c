#!/usr/bin/env python3
"""python_fit: a fit from numpy arrays in the Python module against `sidc fit` on the same record.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_fit.py --sidc build/cli/sidc [--rows 1e7] [--runs 3] [--keep]

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
Relies on: numpy and the module (python/), the sidc binary. Writes only into --dir.
"""
import argparse
import os
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
    t = np.arange(rows) * 0.001
    y = 0.8 * np.sin(0.7 * t) + 0.3 * np.sin(1.9 * t + 0.3) + 0.1 * np.sin(3.7 * t)
    dy = 0.56 * np.cos(0.7 * t) + 0.57 * np.cos(1.9 * t + 0.3) + 0.37 * np.cos(3.7 * t)
    ddy = -0.392 * np.sin(0.7 * t) - 1.083 * np.sin(1.9 * t + 0.3) - 1.369 * np.sin(3.7 * t)
    x = ddy + 0.3 * dy + 0.05 * dy**3 + y + 0.5 * y**3 + 0.2 * y**2 * dy
    return {"t": t, "x": x, "y": y}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sidc", required=True, help="the sidc binary")
    parser.add_argument("--rows", type=float, default=1e7)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--dir", default="/tmp/sidc-python-bench")
    parser.add_argument("--keep", action="store_true", help="reuse DIR/record.csv when it has --rows rows")
    a = parser.parse_args()
    rows = int(a.rows)
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
