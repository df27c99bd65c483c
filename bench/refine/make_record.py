#!/usr/bin/env python3
"""The refinement benchmark's record (issue 15: "refinement of a 10^5-sample record with 10
parameters in under 2 s"): a forced oscillator with ten parameters, ten nonlinear terms of y and
y', sampled every 0.01 s for 10^5 samples, noise of 1% of y's standard deviation (seed 1).

Writes DIR/model.sid (the true terms, weak form) and DIR/record.csv, solving the truth with
`sidc simulate` (RK4, 4 steps per sample). Usage: make_record.py SIDC DIR; bench/README.md.
"""
import math
import os
import random
import statistics
import subprocess
import sys

TRUTH = "c=0.3 k=1 k3=0.5 k2=0.1 d3=0.05 e=0.1 g=0.05 h=0.2 j=0.04 b=1"
EQUATION = "y'' + c*y' + k*y + k3*y^3 + k2*y^2 + d3*y'^3 + e*y*y' + g*y'^2*y + h*sin(y) + j*y'^2 = b*x"


def main():
    sidc, out = os.path.abspath(sys.argv[1]), sys.argv[2]
    os.makedirs(out, exist_ok=True)
    header = "input x\noutput y\nparam c, k, k3, k2, d3, e, g, h, j, b\n"
    with open(os.path.join(out, "truth.sid"), "w") as f:
        f.write("model ten_parameters\n" + header + EQUATION + "\n")
    with open(os.path.join(out, "input.csv"), "w") as f:
        f.write("t,x,y\n")
        for i in range(100000):
            t = i * 0.01
            f.write(f"{t:.2f},{math.cos(1.1 * t) + 0.5 * math.sin(2.7 * t) + 0.3 * math.cos(0.37 * t)!r},0\n")
    subprocess.run([sidc, "simulate", "truth.sid", "--data", "input.csv", "--param", ",".join(TRUTH.split()), "--initial", "y=0,y'=0",
                    "--substeps", "4", "-o", "sim.csv"], cwd=out, check=True, stdout=subprocess.DEVNULL)
    lines = open(os.path.join(out, "sim.csv")).read().split("\n")[1:]
    ys = [float(l.split(",")[1]) for l in lines if l]
    xs = [l.split(",")[1] for l in open(os.path.join(out, "input.csv")).read().split("\n")[1:] if l]
    sd = statistics.pstdev(ys)
    rng = random.Random(1)
    with open(os.path.join(out, "record.csv"), "w") as f:
        f.write("t,x,y\n")
        for i, y in enumerate(ys):
            f.write(f"{i * 0.01:.2f},{xs[i]},{y + rng.gauss(0, 0.01 * sd)!r}\n")
    with open(os.path.join(out, "model.sid"), "w") as f:
        f.write("model ten_parameters\n" + header + 'data "record.csv"\nset form = weak\n' + EQUATION + "\n")


if __name__ == "__main__":
    main()
