#!/usr/bin/env python3
"""Writes the two known-truth records of this example (they are checked in; this says how they were
made): y'' + c(t) y' + k(t) y = x(t) from rest, x a sum of three sines, solved by classical RK4 with
20 substeps a sample, sampled every 0.01 for 100 time units, 0.1% Gaussian noise (of y's standard
deviation) added to y.

  drift.csv: c = 0.4, k(t) = 4 (1 + 0.5 t / 100)   (stiffness drifting linearly by half)
  jump.csv:  k = 4, c(t) = 0.3 before t = 50, 0.9 after   (damping jumping once)

Standard library only: python3 make_records.py
"""
import math
import random


def forcing(t):
    return math.sin(0.7 * t) + 0.6 * math.sin(2.3 * t + 1) + 0.4 * math.sin(4.1 * t + 2)


def record(c, k, path, seed, T=100.0, h=0.01, substeps=20, noise=0.001):
    n = int(round(T / h)) + 1
    y, v = 0.0, 0.0
    d = h / substeps

    def f(t, y, v):
        return v, forcing(t) - c(t) * v - k(t) * y

    ts, ys = [], []
    for s in range(n):
        t = s * h
        ts.append(t)
        ys.append(y)
        for j in range(substeps):
            u = t + j * d
            a1, b1 = f(u, y, v)
            a2, b2 = f(u + d / 2, y + d / 2 * a1, v + d / 2 * b1)
            a3, b3 = f(u + d / 2, y + d / 2 * a2, v + d / 2 * b2)
            a4, b4 = f(u + d, y + d * a3, v + d * b3)
            y += d / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            v += d / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
    mean = sum(ys) / n
    sd = math.sqrt(sum((q - mean) ** 2 for q in ys) / n)
    rng = random.Random(seed)
    with open(path, "w") as out:
        out.write("t,x,y\n")
        for t, q in zip(ts, ys):
            out.write(f"{t:.2f},{forcing(t)!r},{q + rng.gauss(0, noise * sd)!r}\n")


record(lambda t: 0.4, lambda t: 4 * (1 + 0.5 * t / 100), "drift.csv", 1)
record(lambda t: 0.3 if t < 50 else 0.9, lambda t: 4.0, "jump.csv", 2)
