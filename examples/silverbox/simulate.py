#!/usr/bin/env python3
"""Simulates fitted Silverbox models from the measured input alone and prints the RMS error
against the measured output on the benchmark's test sections: an output-error check of
parameters that sidc determined from the equation error.

Relies on: python3 with numpy and scipy (Debian: python3-numpy, python3-scipy), SNLS80mV.csv
beside this script, and fit.json files of `sidc fit --out` for models whose first five
parameters are m, d, k1, k3, c0 of  m*y'' + d*y' + k1*y + k3*y^3 + c0 = u  (any form: the
integrated forms fit the same five). Run by hand; no test depends on it.

    python3 simulate.py FIT.json [FIT.json ...]

Method: u and y are interpolated band-limited (FFT resampling, 8 points per sample; the
excitation stops at 200 Hz, below fs/2 = 305 Hz), the state starts from the measured y and y' at
the section's first sample, classical Runge-Kutta runs on the fine grid, and, as the benchmark
does, the first 50 samples of each section are left out of the error.
"""
import json
import math
import os
import sys

import numpy as np
from scipy import signal

FS = 1e7 / 2**14
SECTIONS = {"test multisine [105712, 127400)": (105712, 127400), "arrow full [100, 40575)": (100, 40575)}
UPSAMPLE = 8
SKIP = 50


def simulate(params, u_fine, y_fine, first, last):
    m, d, k1, k3, c0 = params
    h = 1.0 / (FS * UPSAMPLE)
    i0 = first * UPSAMPLE
    y, v = float(y_fine[i0]), float((y_fine[i0 + 1] - y_fine[i0 - 1]) / (2 * h))

    def accel(y, v, u):
        return (u - c0 - d * v - k1 * y - k3 * y ** 3) / m

    out = np.empty(last - first)
    uf = u_fine.tolist()
    for i in range(i0, last * UPSAMPLE):
        if (i - i0) % UPSAMPLE == 0:
            out[(i - i0) // UPSAMPLE] = y
        ua, ub = uf[i], uf[i + 1]
        um = 0.5 * (ua + ub)
        a1 = accel(y, v, ua)
        y2, v2 = y + 0.5 * h * v, v + 0.5 * h * a1
        a2 = accel(y2, v2, um)
        y3, v3 = y + 0.5 * h * v2, v + 0.5 * h * a2
        a3 = accel(y3, v3, um)
        y4, v4 = y + h * v3, v + h * a3
        a4 = accel(y4, v4, ub)
        y += h / 6 * (v + 2 * v2 + 2 * v3 + v4)
        v += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    record = np.genfromtxt(os.path.join(here, "SNLS80mV.csv"), delimiter=",", skip_header=1, usecols=(0, 1))
    u, y = record[:, 0], record[:, 1]
    u_fine = signal.resample(u, len(u) * UPSAMPLE)
    y_fine = signal.resample(y, len(y) * UPSAMPLE)
    for path in sys.argv[1:]:
        with open(path) as f:
            fit = json.load(f)
        group = fit["groups"][0]
        estimates = {p["name"]: p["estimate"] for p in group["parameters"]}
        params = [estimates.get(name, 0.0) for name in ("m", "d", "k1", "k3", "c0")]
        arc = fit["settings"]["derivative"]
        label = f"{fit['model']} (savgol({arc['window']}, {arc['order']}), {fit['settings']['second_derivative']})"
        for name, (first, last) in SECTIONS.items():
            error = (simulate(params, u_fine, y_fine, first, last) - y[first:last])[SKIP:]
            print(f"{label}: {name}: RMS error {1e3 * math.sqrt(np.mean(error ** 2)):.3f} mV, "
                  f"largest {1e3 * np.max(np.abs(error)):.2f} mV (output s.d. {1e3 * np.std(y[first:last]):.1f} mV)")


if __name__ == "__main__":
    sys.exit(main())
