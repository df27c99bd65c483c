#!/usr/bin/env python3
"""`sidc export --as c|python` against sidc's own solution of the same fitted equations.

For each model: fit it (`sidc fit --out`), export the fit as C and as Python, compile the C with the
system compiler, and take one classical RK4 step from a chosen state with each exported
right-hand side; `sidc simulate --params fit.json` takes the same step (RK4, one substep, no
switch inside it; the step is the record's, as simulate takes the record's grid). The three results agree to 1e-12 of their size only if the exported equations
and numbers are sidc's. `--as latex` must name every parameter's value.

Usage: export_test.py SIDC_BINARY SOURCE_DIR   (SOURCE_DIR: the repository root)
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
void sidc_rhs(double t, const double *state, const double *inputs, double *dstate);
int main(int argc, char **argv) {
  int n = argc - 3;
  double t = atof(argv[1]), h = atof(argv[2]), x[16], k1[16], k2[16], k3[16], k4[16], s[16];
  for (int i = 0; i < n; ++i) x[i] = atof(argv[3 + i]);
  sidc_rhs(t, x, 0, k1);
  for (int i = 0; i < n; ++i) s[i] = x[i] + 0.5 * h * k1[i];
  sidc_rhs(t + 0.5 * h, s, 0, k2);
  for (int i = 0; i < n; ++i) s[i] = x[i] + 0.5 * h * k2[i];
  sidc_rhs(t + 0.5 * h, s, 0, k3);
  for (int i = 0; i < n; ++i) s[i] = x[i] + h * k3[i];
  sidc_rhs(t + h, s, 0, k4);
  for (int i = 0; i < n; ++i) printf("%.17g\n", x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]));
  return 0;
}
"""

PY_DRIVER = r"""
import sys
sys.path.insert(0, sys.argv[1])
import rhs as m
t, h = float(sys.argv[2]), float(sys.argv[3])
x = [float(v) for v in sys.argv[4:]]
f = m.rhs
k1 = f(t, x)
k2 = f(t + h / 2, [a + h / 2 * b for a, b in zip(x, k1)])
k3 = f(t + h / 2, [a + h / 2 * b for a, b in zip(x, k2)])
k4 = f(t + h, [a + h * b for a, b in zip(x, k3)])
for i in range(len(x)):
    print(repr(x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])))
"""


def run(cmd, cwd):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stdout}\n{r.stderr}")
    return r.stdout


def check(sidc, work, model, state, t, h):
    """state: list of (name, order, value) in the exported state's order."""
    run([sidc, "fit", model, "--no-validate", "--out", "fit"], work)
    fit = json.load(open(os.path.join(work, "fit", "fit.json")))
    g = fit["groups"][0]
    p = len(g["parameters"])
    assert len(g["covariance"]) == p and all(len(row) == p for row in g["covariance"]), "covariance is not p x p"
    for i in range(p):
        assert g["correlation"][i][i] in (1.0, "nan"), f"correlation diagonal {g['correlation'][i][i]}"
        assert all(v == "nan" or -1 - 1e-9 <= v <= 1 + 1e-9 for v in g["correlation"][i]), "a correlation outside [-1, 1]"
    run([sidc, "export", "fit/fit.json", "--as", "c", "-o", "rhs.c"], work)
    run([sidc, "export", "fit/fit.json", "--as", "python", "-o", "rhs.py"], work)
    latex = run([sidc, "export", "fit/fit.json", "--as", "latex"], work)
    for q in g["parameters"]:
        assert q["name"].replace("_", "\\_") in latex, f"LaTeX lacks parameter {q['name']}"
    open(os.path.join(work, "driver.c"), "w").write(DRIVER)
    open(os.path.join(work, "driver.py"), "w").write(PY_DRIVER)
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    run([compiler, "-std=c99", "-Wall", "-Wextra", "-Werror", "-O0", "rhs.c", "driver.c", "-lm", "-o", "driver"], work)
    values = [str(v) for _, _, v in state]
    c_step = [float(v) for v in run(["./driver", str(t), str(h)] + values, work).split()]
    py_step = [float(v) for v in run([sys.executable, "driver.py", work, str(t), str(h)] + values, work).split()]
    initial = []
    for name, order, v in state:
        initial += ["--initial", f"{name}{chr(39) * order}={v!r}"]
    run([sidc, "simulate", model, "--params", "fit/fit.json", "--t0", str(t), "--t1", str(t + h),
         "--substeps", "1", "-o", "sim.csv"] + initial, work)
    rows = list(csv.DictReader(open(os.path.join(work, "sim.csv"))))
    assert len(rows) == 2, f"simulate gave {len(rows)} rows"
    worst = 0.0
    for i, (name, order, _) in enumerate(state):
        if order != 0:
            continue  # the CSV holds the outputs only
        sidc_value = float(rows[1][name])
        for got, what in ((c_step[i], "C"), (py_step[i], "Python")):
            error = abs(got - sidc_value) / max(1.0, abs(sidc_value))
            worst = max(worst, error)
            if error > 1e-12:
                sys.exit(f"{model}: {what} export gives {name} = {got!r} after one RK4 step, sidc simulate {sidc_value!r}")
    print(f"{model}: C and Python exports agree with sidc simulate to {worst:.1e} (relative) after one RK4 step")


def main():
    sidc, root = os.path.abspath(sys.argv[1]), sys.argv[2]
    with tempfile.TemporaryDirectory() as work:
        # Eq. 4-1.2's piecewise damper (guards, powers, a defined sine input) on Appendix A.
        for f in ("system_4_1_1.sid", "appendix_a.csv"):
            shutil.copy(os.path.join(root, "examples", "thesis-4-1", f), work)
        check(sidc, work, "system_4_1_1.sid", [("y", 0, 0.1), ("y", 1, 10.0)], 0.3, 0.01)
    with tempfile.TemporaryDirectory() as work:
        # Coupled outputs: a record simulated from known values, fitted, exported.
        text = open(os.path.join(root, "tests", "cli", "export", "coupled.sid")).read()
        open(os.path.join(work, "coupled.sid"), "w").write(text)
        # The truth without its data statement: simulated on a grid of its own, written as the record.
        open(os.path.join(work, "truth.sid"), "w").write("".join(l for l in text.splitlines(True) if not l.startswith("data ")))
        run([sidc, "simulate", "truth.sid", "--param", "m1=1", "--param", "c1=0.4", "--param", "k1=3", "--param", "d1=0.5",
             "--param", "m2=2", "--param", "c2=0.3", "--param", "k2=5", "--initial", "y=1", "--initial", "z=-0.5",
             "--t1", "20", "--step", "0.01", "--substeps", "4", "-o", "coupled.csv"], work)
        check(sidc, work, "coupled.sid", [("y", 0, 0.3), ("y", 1, -0.2), ("z", 0, 0.1), ("z", 1, 0.7)], 1.0, 0.01)
    with tempfile.TemporaryDirectory() as work:
        # A nonlinear parameter (`param L = 2` inside `sin(L*theta)`): declared by name with the value
        # the fit held it at, and named where it stands.
        golden = os.path.join(root, "tests", "golden", "fit")
        shutil.copy(os.path.join(golden, "nonlinear_refined.sid"), os.path.join(work, "pendulum.sid"))
        shutil.copy(os.path.join(golden, "nonlinear_refined.files", "record.csv"), work)
        check(sidc, work, "pendulum.sid", [("theta", 0, 0.4), ("theta", 1, -0.3)], 2.0, 0.02)
        held = json.load(open(os.path.join(work, "fit", "fit.json")))["nonlinear_parameters"]["parameters"][0]["held"]
        code = open(os.path.join(work, "rhs.c")).read()
        assert f"static const double L = {held!r};" in code and "sin(L*state[0])" in code, "the C export does not name L"
    with tempfile.TemporaryDirectory() as work:
        refusals(sidc, root, work)
    return 0


def refused(sidc, work, args, code, words):
    r = subprocess.run([sidc] + args, cwd=work, capture_output=True, text=True)
    if r.returncode != code or words not in r.stderr or r.stdout:
        sys.exit(f"sidc {' '.join(args)}: expected exit {code} and `{words}` on stderr, got {r.returncode}:\n{r.stdout}{r.stderr}")


def refusals(sidc, root, work):
    """What cannot be exported is refused with a message, not written wrong."""
    shutil.copy(os.path.join(root, "tests", "golden", "fit", "no_validate.files", "train.csv"), work)
    # An initial value y(0) is a number only the record knows: C and Python cannot have it.
    open(os.path.join(work, "initial.sid"), "w").write(
        'model initial\ninput u\noutput y\nparam m, c, k\ndata "train.csv" (t = "t", u = "u", y = "y")\nset form = derivative\n'
        "m*y'' + c*y' + k*(y - y(0)) = u\n")
    run([sidc, "fit", "initial.sid", "--no-validate", "--out", "fit"], work)
    refused(sidc, work, ["export", "fit/fit.json", "--as", "c"], 1, "error: cannot export the fitted model: the equations use the initial value `y(...)`")
    run([sidc, "export", "fit/fit.json", "--as", "latex", "-o", "initial.tex"], work)
    # A fit.json without the model's text (written before it carried one).
    fit = json.load(open(os.path.join(work, "fit", "fit.json")))
    del fit["model_source"]
    json.dump(fit, open(os.path.join(work, "old.json"), "w"))
    refused(sidc, work, ["export", "old.json", "--as", "python"], 1, "does not hold the model's text")
    refused(sidc, work, ["export", "fit/fit.json", "--as", "fortran"], 2, "error: --as: fortran not in {c,python,latex}")
    print("refusals: y(0) refused for C, written for LaTeX; a fit.json without model_source refused; --as fortran a usage error")


if __name__ == "__main__":
    sys.exit(main())
