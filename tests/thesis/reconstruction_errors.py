#!/usr/bin/env python3
"""The largest errors of the reconstructed damper and spring (thesis Table 4-1.3, Figures 4-1.11
and 4-1.12) from the parameters sidc fitted, as docs/thesis-reproduction.md reports them.

Relies on: Python 3 standard library; fit.json files written by `sidc fit --out DIR` for a
section 4-1 model whose damper and spring terms are written c1[k]*y'^p*[y' <= 0],
c2[k]*y'^p*[y' >= 0], k1[k]*y^p*[y <= 0], k2[k]*y^p*[y >= 0] (each possibly inside int(...), the
integrated form 4-1.11). The power of every parameter is read from the fitted equation text, so
any row of Table 4-1.2 works. Guarantees: E = observed - approximated (eq. 4-1.4) on a grid of
step 0.001 over the thesis' fitted regions -25 < y' <= 0, 0 <= y' < 16, -2 < y <= 0,
0 <= y < 2 against the true functions of eq. 4-1.2; printed is the E of largest magnitude with
its sign and where it occurs, and %E by eq. 4-1.5 with the thesis' divisors (c(-y')max = -51.6,
c(+y')max = 57.0, k(-y)max = -72.0, k(+y)max = 48.0). Not a ctest test (python3 is not
guaranteed on a fresh Debian).

Usage: reconstruction_errors.py FIT.json [FIT.json ...]
"""
import json
import re
import sys

TRUE_MASS = 0.051813


def true_damper(v):  # eq. 4-1.2
    return 0.5 * (v + 0.005 * v ** 3) if v <= 0 else v + 0.010 * v ** 3


def true_spring(u):  # eq. 4-1.2
    return 30.0 * (u - 0.10 * u ** 2)


# name, variable (y' or y), fitted region (open end excluded, as the thesis writes it), divisor
PIECES = [
    ("c1", "y'", (-25.0, 0.0), true_damper, -51.6, "E[c(-y')]max"),
    ("c2", "y'", (0.0, 16.0), true_damper, 57.0, "E[c(+y')]max"),
    ("k1", "y", (-2.0, 0.0), true_spring, -72.0, "E[k(-y)]max"),
    ("k2", "y", (0.0, 2.0), true_spring, 48.0, "E[k(+y)]max"),
]

TERM = re.compile(r"\b(c1|c2|k1|k2)\[(\d+)\]\*(?:int\()?(y'?)(?:\^(\d+))?\*\[")


def powers_from_equation(text):
    """{parameter name: (variable, power)} from the fitted equation's text."""
    out = {}
    for family, index, variable, exponent in TERM.findall(text):
        out[f"{family}[{index}]"] = (variable, int(exponent) if exponent else 1)
    return out


def region_grid(lo, hi, step=0.001):
    """Points of a region whose end away from zero is open (-25 < y' <= 0, 0 <= y < 2, ...)."""
    n = round((hi - lo) / step)
    points = [lo + i * step for i in range(n + 1)]
    return points[1:] if lo < 0 else points[:-1]


def report(path):
    with open(path) as f:
        fit = json.load(f)
    group = fit["groups"][0]
    powers = powers_from_equation(group["equations"][0]["text"])
    estimates = {p["name"]: p["estimate"] for p in group["parameters"]}
    record = group["records"][0]
    m = estimates["m"]
    print(f"{path}: model {fit['model']}, Delta = {record['step']:.3f}, n = {group['statistics']['n']}, "
          f"G(a) = {group['statistics']['G']:.6g}")
    print(f"  m = {m:.6f}, %E[m] = {abs(TRUE_MASS - m) / TRUE_MASS * 100:.2f}")
    for family, variable, (lo, hi), truth, divisor, label in PIECES:
        terms = [(estimates[name], p) for name, (var, p) in powers.items()
                 if name.startswith(family + "[") and var == variable]
        if not terms:
            raise SystemExit(f"{path}: no {family} terms in {group['equations'][0]['text']}")
        worst, at = 0.0, None
        for v in region_grid(lo, hi):
            e = truth(v) - sum(a * v ** p for a, p in terms)  # eq. 4-1.4
            if abs(e) > abs(worst):
                worst, at = e, v
        print(f"  {label:13} = {worst:+8.2f} at {variable} = {at:+7.3f}, "
              f"%E = {abs(worst / divisor) * 100:5.1f}")


def main():
    if len(sys.argv) < 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    for path in sys.argv[1:]:
        report(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
