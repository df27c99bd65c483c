#!/usr/bin/env python3
"""Thesis section 4-1 rebuilt by hand, independently of sidc, to explain where sidc and the
thesis differ (docs/thesis-reproduction.md). Not a ctest test: python3 is not guaranteed on a
fresh Debian, and nothing here is needed to check sidc (tests/thesis/ does that in C++).

Relies on: Python 3.8+ standard library only (decimal, math, csv, json), and
examples/thesis-4-1/appendix_a.csv. Guarantees: the design matrices of Table 4-1.2 (eq. 4-1.8)
and of eq. 4-1.11 are rebuilt from the model definitions and the Appendix A record with the
thesis' operators (eq. 3-1.7, applied twice for y'', eq. 3-1.8; Simpson integration as sidc's
runtime/operators/simpson.hpp documents it), and solved in decimal arithmetic of any precision: 50 digits
(the reference, which must match sidc's double-precision QR) or 8 digits (the IBM 1620's word,
the thesis' own explanation of its rows 4-6).

Subcommands (run from anywhere; see docs/thesis-reproduction.md for their output):
  table-4-1-2 [--results DIR]   G(a) and m of the 8 combinations at both Delta, 50 digits;
                                with DIR (holding <row>.<every>/fit.json from sidc fit --out)
                                also sidc's numbers and the relative difference.
  eight-digit                   the same least squares, normal equations formed and solved in
                                8-significant-digit decimal arithmetic (several 1964 variants).
  integrated                    eq. 4-1.11 (odd row) under variations of rule, input, t0, Delta.
  integrated-table              eq. 4-1.11 for all eight combinations, 50 and 8 digits.
  quadrants                     Table 4-1.1 counted several ways.
"""
import argparse
import csv
import decimal
import json
import math
import os
import sys
from decimal import Decimal

HERE = os.path.dirname(os.path.abspath(__file__))
APPENDIX_A = os.path.join(HERE, "..", "..", "examples", "thesis-4-1", "appendix_a.csv")

# Table 4-1.2: the powers of y' (damper) and y (spring) in each half plane (eq. 4-1.7).
COMBINATIONS = [
    ("odd", [1, 3, 5], (73, 16)),
    ("even", [2, 4, 6], (480, 261)),
    ("first_order", [1], (1874, 815)),
    ("second_order", [1, 2], (154, 119)),
    ("third_order", [1, 2, 3], (74, 23)),
    ("fourth_order", [1, 2, 3, 4], (90, 17)),
    ("fifth_order", [1, 2, 3, 4, 5], (1286, 24785)),
    ("sixth_order", [1, 2, 3, 4, 5, 6], (62616, 164132)),
]

# eq. 3-1.7: 7-point cubic moving arc, first derivative, weights for y[n-3..n+3] over 252 Delta.
FIRST_7_CUBIC = [22, -67, -58, 0, 58, 67, -22]


def read_appendix_a():
    with open(APPENDIX_A, newline="") as f:
        rows = list(csv.DictReader(f))
    return {name: [row[name] for row in rows] for name in rows[0]}


def context(digits, rounding=decimal.ROUND_HALF_EVEN):
    return decimal.Context(prec=digits, rounding=rounding, Emin=-999999, Emax=999999)


def moving_arc_first(values, delta, ctx):
    """eq. 3-1.7 at every n with 3 neighbours each side; None at the edges."""
    out = [None] * len(values)
    for n in range(3, len(values) - 3):
        if any(values[n + i - 3] is None for i in range(7)):
            continue
        acc = Decimal(0)
        for i, w in enumerate(FIRST_7_CUBIC):
            acc = ctx.add(acc, ctx.multiply(Decimal(w), values[n + i - 3]))
        out[n] = ctx.divide(acc, ctx.multiply(Decimal(252), delta))
    return out


def exact_input(t_text, ctx):
    """x = 60 sin(4 pi t) (eq. 4-1.2), as the thesis evaluated it, rounded to the context."""
    return ctx.plus(Decimal(repr(60.0 * math.sin(4.0 * math.pi * float(t_text)))))


def power(v, p, ctx):
    acc = Decimal(1)
    for _ in range(p):
        acc = ctx.multiply(acc, v)
    return acc


def record(every, ctx, input_from_table=False, velocity="eq. 3-1.7"):
    """The Appendix A record at Delta = 0.010 * every: t, y, y', y'', x. `velocity` other than
    eq. 3-1.7 is for diagnosis only: "table" takes y' from Appendix A's ydot column (which the
    thesis did not use), "eq. 3-1.3" from the 5-point quadratic, "smoothed" applies eq. 3-1.6
    to y first (y itself stays as observed)."""
    data = read_appendix_a()
    keep = range(0, len(data["t"]), every)
    t = [data["t"][i] for i in keep]
    y = [Decimal(data["y"][i]) for i in keep]
    delta = Decimal("0.01") * every
    if velocity == "eq. 3-1.7":
        y1 = moving_arc_first(y, delta, ctx)
    elif velocity == "table":
        y1 = [Decimal(data["ydot"][i]) for i in keep]
        y1[:3] = [None] * 3  # same rows as the estimate, so only the values differ
    elif velocity == "eq. 3-1.3":
        y1 = [None] * len(y)
        for n in range(2, len(y) - 2):
            y1[n] = ctx.divide(2 * (y[n + 2] - y[n - 2]) + (y[n + 1] - y[n - 1]), 10 * delta)
        y1[2] = None
    elif velocity == "smoothed":
        smooth = [None] * len(y)
        for n in range(3, len(y) - 3):  # eq. 3-1.6
            smooth[n] = ctx.divide(7 * y[n] + 6 * (y[n + 1] + y[n - 1]) + 3 * (y[n + 2] + y[n - 2])
                                   - 2 * (y[n + 3] + y[n - 3]), Decimal(21))
        y1 = moving_arc_first(smooth, delta, ctx)
    else:
        raise ValueError(velocity)
    y2 = moving_arc_first(y1, delta, ctx)  # eq. 3-1.8 = eq. 3-1.7 applied twice
    x = [Decimal(data["x"][i]) if input_from_table else exact_input(data["t"][i], ctx) for i in keep]
    return {"t": t, "y": y, "y1": y1, "y2": y2, "x": x, "delta": delta}


def half_plane_terms(v, powers, ctx):
    """c1 (v <= 0), c2 (v >= 0) columns for one variable, eq. 4-1.7 with eq. 4-1.9."""
    neg = [power(v, p, ctx) if v <= 0 else Decimal(0) for p in powers]
    pos = [power(v, p, ctx) if v >= 0 else Decimal(0) for p in powers]
    return neg + pos


def derivative_form(every, powers, ctx, to="0.82"):
    """eq. 4-1.8: rows t0 = 6 Delta (tau0 = 3 alpha Delta, alpha = 2) to 0.82; columns
    m, c1[..], c2[..], k1[..], k2[..] in sidc's order; right side x."""
    rec = record(every, ctx)
    X, b, rows = [], [], []
    for n, t in enumerate(rec["t"]):
        if rec["y2"][n] is None or Decimal(t) > Decimal(to):
            continue
        X.append([rec["y2"][n]] + half_plane_terms(rec["y1"][n], powers, ctx)
                 + half_plane_terms(rec["y"][n], powers, ctx))
        b.append(rec["x"][n])
        rows.append(n)
    return X, b, rec, rows


def cumulative(values, h, rule):
    """Cumulative integral from sample 0 (runtime/operators/simpson.hpp, the same formulas)."""
    f = [float(v) for v in values]
    out = [0.0] * len(f)
    for i in range(1, len(f)):
        if rule == "trapezoid" or len(f) < 3:
            out[i] = out[i - 1] + h / 2 * (f[i - 1] + f[i])
        elif rule == "simpson":
            if i % 2 == 0:
                out[i] = out[i - 2] + h / 3 * (f[i - 2] + 4 * f[i - 1] + f[i])
            elif i >= 3:
                out[i] = out[i - 1] + h / 24 * (f[i - 3] - 5 * f[i - 2] + 19 * f[i - 1] + 9 * f[i])
            else:
                out[i] = out[i - 1] + h / 24 * (9 * f[0] + 19 * f[1] - 5 * f[2] + f[3])
        elif rule == "simpson-trapezoid-odd":
            # Simpson on the even samples; odd samples by one trapezoid (a common 1960s patch).
            if i % 2 == 0:
                out[i] = out[i - 2] + h / 3 * (f[i - 2] + 4 * f[i - 1] + f[i])
            else:
                out[i] = out[i - 1] + h / 2 * (f[i - 1] + f[i])
        else:
            raise ValueError(rule)
    return out


def integrated_form(every, powers, ctx, rule="simpson", input_from_table=False, t0=None,
                    to="0.82", even_only=False, velocity="eq. 3-1.7"):
    """eq. 4-1.11: m y' + int c1 + int c2 + int k1 + int k2 + a25 = int x, integrals from t0
    (default tau0 = 3 Delta, alpha = 1). even_only keeps the rows an even number of steps
    after t0 (where pure composite Simpson is defined)."""
    rec = record(every, ctx, input_from_table, velocity)
    h = float(rec["delta"])
    first = next(n for n, v in enumerate(rec["y1"]) if v is not None)
    if t0 is not None:
        first = next(n for n, t in enumerate(rec["t"]) if Decimal(t) >= Decimal(t0))
    last = max(n for n, t in enumerate(rec["t"]) if Decimal(t) <= Decimal(to))
    span = range(first, last + 1)
    columns = [half_plane_terms(rec["y1"][n], powers, ctx) + half_plane_terms(rec["y"][n], powers, ctx)
               for n in span]
    integrals = [cumulative([row[j] for row in columns], h, rule) for j in range(len(columns[0]))]
    x_int = cumulative([rec["x"][n] for n in span], h, rule)
    X, b = [], []
    for i, n in enumerate(span):
        if even_only and i % 2:
            continue
        X.append([rec["y1"][n]] + [Decimal(repr(col[i])) for col in integrals] + [Decimal(1)])
        b.append(Decimal(repr(x_int[i])))
    return X, b


def scale_columns(X, ctx):
    """Section 3-2 scale factors: each column divided by its largest magnitude (a power of ten
    in 1964 practice would do the same job; this is the generous choice)."""
    s = [max(abs(row[j]) for row in X) or Decimal(1) for j in range(len(X[0]))]
    return [[ctx.divide(row[j], s[j]) for j in range(len(row))] for row in X], s


def normal_equations(X, b, ctx):
    """eq. 2-1.8 as 1964 practice formed it: A = X'X, r = X'b, every product and sum rounded."""
    p = len(X[0])
    A = [[Decimal(0)] * p for _ in range(p)]
    r = [Decimal(0)] * p
    for row, bi in zip(X, b):
        for j in range(p):
            if row[j] == 0:
                continue
            r[j] = ctx.add(r[j], ctx.multiply(row[j], bi))
            for k in range(j, p):
                A[j][k] = ctx.add(A[j][k], ctx.multiply(row[j], row[k]))
    for j in range(p):
        for k in range(j):
            A[j][k] = A[k][j]
    return A, r


def gauss_solve(A, r, ctx, pivoting=True):
    """Gaussian elimination (partial pivoting unless told otherwise), back substitution."""
    p = len(A)
    M = [A[j][:] + [r[j]] for j in range(p)]
    for c in range(p):
        if pivoting:
            piv = max(range(c, p), key=lambda i: abs(M[i][c]))
            M[c], M[piv] = M[piv], M[c]
        if M[c][c] == 0:
            return None
        for i in range(c + 1, p):
            f = ctx.divide(M[i][c], M[c][c])
            for k in range(c, p + 1):
                M[i][k] = ctx.subtract(M[i][k], ctx.multiply(f, M[c][k]))
    a = [Decimal(0)] * p
    for c in reversed(range(p)):
        acc = M[c][p]
        for k in range(c + 1, p):
            acc = ctx.subtract(acc, ctx.multiply(M[c][k], a[k]))
        a[c] = ctx.divide(acc, M[c][c])
    return a


def gauss_jordan_inverse_solve(A, r, ctx):
    """The thesis' "matrix inversion routine": Gauss-Jordan inverse with partial pivoting, then
    a = A^-1 r, all in the given arithmetic."""
    p = len(A)
    M = [A[j][:] + [Decimal(int(j == k)) for k in range(p)] for j in range(p)]
    for c in range(p):
        piv = max(range(c, p), key=lambda i: abs(M[i][c]))
        M[c], M[piv] = M[piv], M[c]
        if M[c][c] == 0:
            return None
        d = M[c][c]
        M[c] = [ctx.divide(v, d) for v in M[c]]
        for i in range(p):
            if i != c and M[i][c] != 0:
                f = M[i][c]
                M[i] = [ctx.subtract(vi, ctx.multiply(f, vc)) for vi, vc in zip(M[i], M[c])]
    inv = [row[p:] for row in M]
    a = []
    for j in range(p):
        acc = Decimal(0)
        for k in range(p):
            acc = ctx.add(acc, ctx.multiply(inv[j][k], r[k]))
        a.append(acc)
    return a


def residual_sum(X, b, a, ctx):
    """G(a), eq. 2-1.7 with unit weights, in the given arithmetic."""
    g = Decimal(0)
    for row, bi in zip(X, b):
        e = ctx.subtract(sum((ctx.multiply(xj, aj) for xj, aj in zip(row, a)), Decimal(0)), bi)
        e = ctx.plus(e)
        g = ctx.add(g, ctx.multiply(e, e))
    return g


def least_squares(X, b, digits, rounding=decimal.ROUND_HALF_EVEN, method="gauss", scaled=False):
    """Parameters of the least-squares fit in `digits`-digit arithmetic, in the caller's
    (unscaled) units, and G(a) evaluated exactly (50 digits) at those parameters."""
    ctx = context(digits, rounding)
    Xr = [[ctx.plus(v) for v in row] for row in X]
    br = [ctx.plus(v) for v in b]
    s = None
    if scaled:
        Xr, s = scale_columns(Xr, ctx)
    A, r = normal_equations(Xr, br, ctx)
    if method == "gauss":
        a = gauss_solve(A, r, ctx)
    elif method == "gauss-no-pivoting":
        a = gauss_solve(A, r, ctx, pivoting=False)
    elif method == "gauss-jordan":
        a = gauss_jordan_inverse_solve(A, r, ctx)
    else:
        raise ValueError(method)
    if a is None:
        return None, None
    if s is not None:
        a = [ctx.divide(aj, sj) for aj, sj in zip(a, s)]
    return a, residual_sum(X, b, a, context(50))


REFERENCE = 50  # digits: far beyond double, so this is the exact least-squares answer here


def cmd_table(args):
    ref = context(REFERENCE)
    print(f"{'row':14} {'Delta':>6} {'n':>3} {'p':>3} {'G (50 digits)':>14} {'thesis':>7} "
          f"{'m':>10}" + ("  sidc G          rel.diff  sidc m      rel.diff" if args.results else ""))
    for name, powers, thesis in COMBINATIONS:
        for every in (1, 2):
            X, b, _, _ = derivative_form(every, powers, ref)
            a, g = least_squares(X, b, REFERENCE, scaled=True)
            line = (f"{name:14} {0.01 * every:6.3f} {len(X):3d} {len(X[0]):3d} {float(g):14.6f} "
                    f"{thesis[every - 1]:7d} {float(a[0]):10.7f}")
            if args.results:
                with open(os.path.join(args.results, f"{name}.{every}", "fit.json")) as f:
                    group = json.load(f)["groups"][0]
                sg = group["statistics"]["G"]
                sm = group["parameters"][0]["estimate"]
                line += f"  {sg:14.9f} {abs(sg - float(g)) / float(g):8.1e}  {sm:.8f} " \
                        f"{abs(sm - float(a[0])) / abs(float(a[0])):8.1e}"
            print(line)


def cmd_eight_digit(args):
    rows = [c for c in COMBINATIONS if args.rows is None or c[0] in args.rows]
    for title, options in EIGHT_DIGIT_VARIANTS:
        print(title)
        print(f"  {'row':14} {'p':>3} {'G, D=0.010':>14} {'G, D=0.020':>14}   thesis")
        for name, powers, thesis in rows:
            gs = []
            for every in (1, 2):
                # the design matrix itself computed in 8-digit arithmetic (y', y'', powers, x)
                rounding = options.get("rounding", decimal.ROUND_HALF_EVEN)
                X, b, _, _ = derivative_form(every, powers, context(8, rounding))
                a, g = least_squares(X, b, 8, **options)
                gs.append("singular" if g is None else f"{float(g):14.2f}")
            print(f"  {name:14} {1 + 4 * len(powers):3d} {gs[0]:>14} {gs[1]:>14}   "
                  f"{thesis[0]} / {thesis[1]}")
        sys.stdout.flush()


# The IBM 1620's FORTRAN carried 8 significant decimal digits; how it rounded and which
# inversion routine the thesis used are not recorded, so several plausible ones are tried.
EIGHT_DIGIT_VARIANTS = [
    ("8 digits, rounded, Gauss with pivoting, unscaled", dict(method="gauss")),
    ("8 digits, rounded, Gauss-Jordan inverse, unscaled", dict(method="gauss-jordan")),
    ("8 digits, truncated, Gauss-Jordan inverse, unscaled",
     dict(method="gauss-jordan", rounding=decimal.ROUND_DOWN)),
    ("8 digits, rounded, Gauss-Jordan inverse, columns scaled (sec. 3-2)",
     dict(method="gauss-jordan", scaled=True)),
    ("8 digits, truncated, Gauss-Jordan inverse, columns scaled (sec. 3-2)",
     dict(method="gauss-jordan", scaled=True, rounding=decimal.ROUND_DOWN)),
]


def cmd_integrated(args):
    ref = context(REFERENCE)
    powers = [1, 3, 5]
    print(f"{'variant':60} {'n':>3} {'G(a)':>10} {'m':>10} {'%E[m]':>6}")
    cases = []
    for every in (1, 2):
        d = f"D={0.01 * every:.3f}"
        cases += [
            (f"{d} Simpson (sidc default), exact x, t0 = 3 Delta", every, dict()),
            (f"{d} trapezoid", every, dict(rule="trapezoid")),
            (f"{d} Simpson, odd samples by trapezoid", every, dict(rule="simpson-trapezoid-odd")),
            (f"{d} Simpson, rows at even offsets from t0 only", every, dict(even_only=True)),
            (f"{d} Simpson, x from the table column", every, dict(input_from_table=True)),
            (f"{d} Simpson, t0 = 0.06", every, dict(t0="0.06")),
            (f"{d} Simpson, t0 = 0.12", every, dict(t0="0.12")),
            (f"{d} Simpson, window to 1.00 - 3 Delta", every,
             dict(to=f"{1.0 - 3 * 0.01 * every:.2f}")),
            (f"{d} Simpson, y' by eq. 3-1.3 (5-point quadratic)", every, dict(velocity="eq. 3-1.3")),
            (f"{d} Simpson, y' of y smoothed by eq. 3-1.6", every, dict(velocity="smoothed")),
            (f"{d} Simpson, y' = Appendix A ydot (diagnosis only)", every, dict(velocity="table")),
            (f"{d} trapezoid, y' = Appendix A ydot (diagnosis only)", every,
             dict(velocity="table", rule="trapezoid")),
        ]
    for title, every, options in cases:
        X, b = integrated_form(every, powers, ref, **options)
        a, g = least_squares(X, b, REFERENCE, scaled=True)
        m = float(a[0])
        print(f"{title:60} {len(X):3d} {float(g):10.5f} {m:10.6f} {abs(m - 0.051813) / 0.051813 * 100:6.2f}")
    print("The sidc default (Simpson, exact x, t0 = 3 Delta) in 8-digit arithmetic:")
    for title, options in EIGHT_DIGIT_VARIANTS:
        for every in (1, 2):
            X, b = integrated_form(every, powers, context(8, options.get("rounding",
                                                                        decimal.ROUND_HALF_EVEN)))
            a, g = least_squares(X, b, 8, **options)
            m = float(a[0])
            print(f"  {title:68} D={0.01 * every:.3f} G={float(g):8.4f} m={m:.6f} "
                  f"%E[m]={abs(m - 0.051813) / 0.051813 * 100:.2f}")


def cmd_integrated_table(args):
    """The eight combinations in the integrated form 4-1.11: the thesis says the odd one again had
    the smallest G(a) at both Delta, which exact least squares cannot give for nested models."""
    names = ["50 digits"] + [title.replace("8 digits, ", "8 d. ") for title, _ in EIGHT_DIGIT_VARIANTS]
    for every in (1, 2):
        print(f"Delta = {0.01 * every:.3f}: G(a) of eq. 4-1.11; columns: " + "; ".join(
            f"({i}) {n}" for i, n in enumerate(names)))
        print(f"  {'row':14} {'p':>3}" + "".join(f"{f'({i})':>11}" for i in range(len(names))))
        for name, powers, _ in COMBINATIONS:
            X, b = integrated_form(every, powers, context(REFERENCE))
            gs = [float(least_squares(X, b, REFERENCE, scaled=True)[1])]
            for _, options in EIGHT_DIGIT_VARIANTS:
                X, b = integrated_form(every, powers, context(8, options.get("rounding",
                                                                            decimal.ROUND_HALF_EVEN)))
                g = least_squares(X, b, 8, **options)[1]
                gs.append(float("nan") if g is None else float(g))
            print(f"  {name:14} {2 + 4 * len(powers):3d}" + "".join(f"{g:11.4g}" for g in gs))


def cmd_quadrants(args):
    ref = context(REFERENCE)
    data = read_appendix_a()

    def quadrant(y, v):
        if y >= 0 and v >= 0:
            return "I"
        if y < 0 and v >= 0:
            return "II"
        if y < 0:
            return "III"
        return "IV"

    for every in (1, 2):
        rec = record(every, ref)
        delta = 0.01 * every
        rows = [n for n, t in enumerate(rec["t"]) if rec["y2"][n] is not None and float(t) <= 0.82]
        by_estimate = {q: 0 for q in ("I", "II", "III", "IV")}
        by_table = dict(by_estimate)
        for n in rows:
            by_estimate[quadrant(rec["y"][n], rec["y1"][n])] += 1
            i = n * every
            by_table[quadrant(Decimal(data["y"][i]), Decimal(data["ydot"][i]))] += 1
        print(f"Delta = {delta:.3f}, t = {rec['t'][rows[0]]} .. {rec['t'][rows[-1]]}, n = {len(rows)}")
        print(f"  quadrants from y and the estimated y' (eq. 3-1.7): {by_estimate}")
        print(f"  quadrants from y and Appendix A's ydot column:     {by_table}")
        flips = [(rec["t"][n], data["ydot"][n * every], f"{float(rec['y1'][n]):.3f}") for n in rows
                 if quadrant(rec["y"][n], rec["y1"][n]) != quadrant(Decimal(data["y"][n * every]),
                                                                    Decimal(data["ydot"][n * every]))]
        print(f"  rows where the two disagree (t, table ydot, estimated y'): {flips}")
        near = [(rec["t"][n], str(rec["y"][n]), f"{float(rec['y1'][n]):.2f}") for n in rows
                if abs(rec["y1"][n]) < 1 or abs(rec["y"][n]) < Decimal("0.1")]
        print(f"  rows next to a quadrant boundary (|y'| < 1 or |y| < 0.1): {near}")


def main():
    parser = argparse.ArgumentParser(
        description="Thesis section 4-1 rebuilt by hand, independently of sidc "
                    "(docs/thesis-reproduction.md).")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("table-4-1-2")
    p.add_argument("--results", help="directory with <row>.<every>/fit.json from sidc fit --out")
    p.set_defaults(run=cmd_table)
    p = sub.add_parser("eight-digit")
    p.add_argument("--rows", nargs="*", help="only these rows of Table 4-1.2")
    p.set_defaults(run=cmd_eight_digit)
    sub.add_parser("integrated").set_defaults(run=cmd_integrated)
    sub.add_parser("integrated-table").set_defaults(run=cmd_integrated_table)
    sub.add_parser("quadrants").set_defaults(run=cmd_quadrants)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
