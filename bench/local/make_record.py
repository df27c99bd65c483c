#!/usr/bin/env python3
"""The record and model of issue 18's local-fit benchmark (bench/README.md, "Local fits").

Writes DIR/record.csv: 10^6 rows (--rows) of t, x, y, step 0.001, of fit_bench's oscillator
(m y'' + c1 y' + c3 y'^3 + s1 y + s3 y^3 + d2 y^2 y' = x) whose linear stiffness s1 drifts from 1 to
1.5 along the record, solved by classical RK4 one step a sample, 12 significant digits; and
DIR/model.sid: fit_bench's 20 candidate operations in derivative form (savgol(7, 3)). A window of
10 time units is 10^4 rows. Standard library only.

  python3 bench/local/make_record.py /tmp/sidc-local-bench [--rows 1e6]
"""
import argparse
import math
import os

parser = argparse.ArgumentParser()
parser.add_argument("dir")
parser.add_argument("--rows", type=float, default=1e6)
args = parser.parse_args()
rows = int(args.rows)
os.makedirs(args.dir, exist_ok=True)
h = 1e-3
T = rows * h
m, c1, c3, s3, d2 = 1.0, 0.3, 0.05, 0.5, 0.2


def force(t):
    return 1.5 * math.sin(0.7 * t) + 0.8 * math.sin(1.9 * t + 0.3) + 0.4 * math.sin(3.7 * t)


def acceleration(t, y, v):
    s1 = 1 + 0.5 * t / T
    return (force(t) - c1 * v - c3 * v * v * v - s1 * y - s3 * y * y * y - d2 * y * y * v) / m


y = v = 0.0
lines = ["t,x,y\n"]
for k in range(rows):
    t = k * h
    lines.append(f"{t:.12g},{force(t):.12g},{y:.12g}\n")
    k1y, k1v = v, acceleration(t, y, v)
    k2y, k2v = v + 0.5 * h * k1v, acceleration(t + 0.5 * h, y + 0.5 * h * k1y, v + 0.5 * h * k1v)
    k3y, k3v = v + 0.5 * h * k2v, acceleration(t + 0.5 * h, y + 0.5 * h * k2y, v + 0.5 * h * k2v)
    k4y, k4v = v + h * k3v, acceleration(t + h, y + h * k3y, v + h * k3v)
    y += h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y)
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
with open(os.path.join(args.dir, "record.csv"), "w") as out:
    out.writelines(lines)
with open(os.path.join(args.dir, "model.sid"), "w") as out:
    out.write("""# bench/local/make_record.py: fit_bench's 20 candidate operations, the linear stiffness s[1] drifting
model local_bench
input  x
output y
param  m, c[1..6], s[1..6], d[1..7]
data "record.csv"
set derivative = savgol(7, 3)
set integrate = 0
m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x
""")
print(f"wrote {args.dir}/record.csv ({rows} rows) and {args.dir}/model.sid")
