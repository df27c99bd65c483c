#!/usr/bin/env python3
"""Fits a compiled Silverbox model on many short windows of the train/validation section and
prints, per physical quantity, the mean and spread over the windows beside the median of sidc's
own standard errors. The spread is an honest error bar (the windows hold different data); sidc's
standard error assumes independent residuals, which a mismatch between the two exposes.

Relies on: python3 (standard library only), a built sidc, models compiled in this folder
(`sidc compile derivative_form.sid` ...), the fit.json format of `sidc fit --out`.

    python3 window_scan.py SIDC MODEL.sidc.json [--length 1.0] [--count 40] [-- extra fit options]
"""
import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile

STEP = 0.0016384                   # 2^14/1e7 s
SECTION = (40650, 105712)          # the benchmark's train/validation section, half open


def fit(sidc, compiled, start, stop, extra, out):
    run = subprocess.run([sidc, "fit", compiled, "--from", repr(start), "--to", repr(stop), "--out", out, *extra],
                         capture_output=True, text=True)
    if run.returncode != 0:
        return None
    with open(out + "/fit.json") as f:
        group = json.load(f)["groups"][0]
    return {p["name"]: (p["estimate"], p["standard_error"]) for p in group["parameters"]}


def physical(p):
    m, d, k1, k3 = (p[name][0] for name in ("m", "d", "k1", "k3"))
    if m <= 0 or k1 <= 0:
        return None
    return {"f_n (Hz)": math.sqrt(k1 / m) / (2 * math.pi), "zeta": d / (2 * math.sqrt(k1 * m)),
            "k1": k1, "k3": k3, "k3/k1": k3 / k1}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("sidc")
    parser.add_argument("compiled")
    parser.add_argument("--length", type=float, default=1.0, help="window length, s")
    parser.add_argument("--count", type=int, default=40, help="number of windows, evenly spread")
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    args = parser.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    first, last = SECTION[0] * STEP, (SECTION[1] - 1) * STEP
    rows, failed = [], 0
    with tempfile.TemporaryDirectory() as out:
        for k in range(args.count):
            start = first + k * (last - first - args.length) / max(args.count - 1, 1)
            p = fit(args.sidc, args.compiled, start, start + args.length, extra, out)
            q = physical(p) if p else None
            if q is None:
                failed += 1
                continue
            rows.append((q, p))
    print(f"{args.compiled}: {len(rows)} windows of {args.length} s ({failed} failed or non-physical)")
    for name in ("f_n (Hz)", "zeta", "k1", "k3", "k3/k1"):
        values = [q[name] for q, _ in rows]
        line = f"  {name:9s} mean {statistics.mean(values):10.4g}  s.d. over windows {statistics.stdev(values):9.3g}"
        if name in ("k1", "k3"):
            line += f"  median sidc std. error {statistics.median(p[name][1] for _, p in rows):9.3g}"
        print(line)
    negative = sum(1 for q, _ in rows if q["zeta"] <= 0)
    print(f"  windows with zeta <= 0: {negative}; with k3 <= 0: {sum(1 for q, _ in rows if q['k3'] <= 0)}")


if __name__ == "__main__":
    sys.exit(main())
