"""The Python module against the sidc binary: the same model and record give the same numbers.

    SIDC_BINARY=build/cli/sidc SIDC_SOURCE_DIR=. PYTHONPATH=build/python python3 -m unittest test_sidc

Relies on: the module built into PYTHONPATH (python/CMakeLists.txt), the binary, the thesis
section 4-1 record (examples/thesis-4-1). Guarantees: fit.json from `FitResult.to_json()` is the
CLI's byte for byte; estimates from numpy arrays (contiguous, strided, float32) agree with the
CLI's fit.json to 1e-12; several records, settings, select and simulate agree with the CLI; every
bad input of the issue (arrays of different lengths, non-float dtypes, NaN, unknown keywords, a
model error) is a Python exception with the CLI's wording; the interpreter lock is released
during a fit; arrays handed back are not copies.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import warnings

import numpy as np

import sidc

BINARY = os.environ["SIDC_BINARY"]
SOURCE = os.environ["SIDC_SOURCE_DIR"]
THESIS = os.path.join(SOURCE, "examples", "thesis-4-1")


def run_cli(*args, cwd=None):
    return subprocess.run([BINARY, *args], capture_output=True, text=True, cwd=cwd)


def read_record(path):
    """The CSV as numpy arrays by column name (columns of a structured array: strided views)."""
    table = np.genfromtxt(path, delimiter=",", names=True)
    return {name: table[name] for name in table.dtype.names}


class Workspace(unittest.TestCase):
    """A copy of examples/thesis-4-1 per test: the CLI writes its files there."""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="sidc-python-")
        for name in ("appendix_a.csv", "quasi_linear.sid", "select_sixth.sid", "system_4_1_1.sid"):
            shutil.copy(os.path.join(THESIS, name), self.dir)
        self.model_path = os.path.join(self.dir, "quasi_linear.sid")
        self.csv = os.path.join(self.dir, "appendix_a.csv")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def cli_fit(self, *args, model=None):
        out = os.path.join(self.dir, "out")
        done = run_cli("fit", model or self.model_path, "--out", out, *args)
        self.assertEqual(done.returncode, 0, done.stderr)
        with open(os.path.join(out, "fit.json")) as f:
            return f.read()

    def assertEstimatesEqual(self, estimates, cli_json, tolerance=1e-12):
        cli = {p["name"]: p["estimate"] for g in json.loads(cli_json)["groups"] for p in g["parameters"]}
        self.assertEqual(sorted(estimates), sorted(cli))
        for name, value in cli.items():
            self.assertLessEqual(abs(estimates[name] - value), tolerance * max(1.0, abs(value)), name)


class FitAgreesWithCli(Workspace):
    def test_fit_json_is_the_clis(self):
        model = sidc.compile(self.model_path)
        result = model.fit()
        self.assertEqual(result.to_json(), self.cli_fit())
        self.assertEqual(result.report().splitlines()[0], f"sidc fit: model `quasi_linear` ({self.model_path})")
        self.assertIn("95% confidence interval", result.report())

    def test_numpy_record_gives_the_clis_estimates(self):
        cli = self.cli_fit()
        record = read_record(self.csv)
        self.assertFalse(record["y"].flags.c_contiguous)  # strided views of the table
        model = sidc.compile(self.model_path)
        strided = model.fit(record)
        self.assertEstimatesEqual(strided.estimates, cli)
        contiguous = model.fit({k: np.ascontiguousarray(v) for k, v in record.items()})
        self.assertEqual(contiguous.estimates, strided.estimates)
        # Everything but the record's name is the same document.
        self.assertEqual(contiguous.to_json(), cli.replace(json.dumps(self.csv)[1:-1], "<arrays>"))

    def test_result_fields(self):
        model = sidc.compile(self.model_path)
        result = model.fit(read_record(self.csv))
        document = json.loads(result.to_json())
        group = document["groups"][0]
        names = [p["name"] for p in group["parameters"]]
        self.assertEqual(list(result.estimates), names)
        self.assertEqual(result.standard_errors["m"], group["parameters"][0]["standard_error"])
        self.assertEqual(result.ci95["m"], tuple(group["parameters"][0]["ci95"]))
        # 80 rows for 14 parameters: too few for Newey-West intervals, and fit.json says why.
        self.assertEqual(result.hac_ci95, {})
        self.assertIn("too few rows", group["hac"]["note"])
        self.assertEqual(result.covariance.shape, (len(names), len(names)))
        np.testing.assert_array_equal(result.covariance, np.array(group["covariance"], dtype=float))
        self.assertEqual(result.G, group["statistics"]["G"])
        self.assertEqual(result.statistics[0]["n"], 80)
        self.assertEqual(result.validation, document["validation"])
        self.assertIsNotNone(result.validation)
        residuals = result.residuals
        self.assertEqual(len(residuals["residual"]), 80)
        np.testing.assert_allclose(residuals["known"] - residuals["fitted"], residuals["residual"], rtol=0, atol=1e-12)
        # G is the sum of the squared residuals (eq. 2-1.7, unweighted here).
        self.assertAlmostEqual(float(np.sum(residuals["residual"] ** 2)), result.G, delta=1e-12 * max(1.0, result.G))

    def test_nonlinear_parameters(self):
        # y = a*exp(-k*x) + b: k held at the value of least G, with a standard error, as fit.json has it.
        path = os.path.join(self.dir, "decay.sid")
        with open(path, "w") as f:
            f.write("model decay\ninput x\noutput y\nparam a, b, k = 0.2\ny = a*exp(-k*x) + b\n")
        x = np.arange(60) * 0.1
        y = 3 * np.exp(-0.7 * x) + 0.5 + 0.05 * np.random.default_rng(7).standard_normal(60)
        result = sidc.compile(path).fit({"x": x, "y": y})
        self.assertEqual(sorted(result.estimates), ["a", "b"])
        k = result.nonlinear["k"]
        self.assertEqual(k["guess"], 0.2)
        self.assertEqual(k["held"], result.document["nonlinear_parameters"]["parameters"][0]["held"])
        self.assertLess(abs(k["held"] - 0.7), 4 * k["standard_error"])
        self.assertAlmostEqual(k["ci95"][1] - k["held"], 1.96 * k["standard_error"])
        self.assertNotIn("refined", k)
        self.assertEqual(sidc.compile(self.model_path).fit(read_record(self.csv)).nonlinear, {})

    def test_settings_are_the_clis_options(self):
        cli = self.cli_fit("--every", "2", "--to", "0.7", "--no-validate", "--derivative", "savgol(5, 2)")
        model = sidc.compile(self.model_path)
        result = model.fit(read_record(self.csv), every=2, to=0.7, no_validate=True, derivative="savgol(5, 2)")
        self.assertEstimatesEqual(result.estimates, cli)
        self.assertIsNone(result.validation)
        self.assertEqual(json.loads(cli)["settings"], json.loads(result.to_json())["settings"])
        self.assertEqual(model.fit(read_record(self.csv), **{"from": 0.1}, no_validate=True).estimates,
                         model.fit(read_record(self.csv), from_=0.1, no_validate=True).estimates)

    def test_noise_check_is_the_clis(self):
        cli = json.loads(self.cli_fit("--no-validate"))
        model = sidc.compile(self.model_path)
        checked = json.loads(model.fit(read_record(self.csv), no_validate=True).to_json())["noise_check"]
        self.assertEqual(cli["noise_check"], checked)
        self.assertIn("parameters", checked)
        self.assertIsNone(json.loads(model.fit(read_record(self.csv), no_validate=True, no_noise_check=True).to_json())["noise_check"])

    def test_isolated_outliers_are_replaced_as_the_cli_replaces_them(self):
        record = read_record(self.csv)
        glitched = dict(record, y=record["y"].copy())
        glitched["y"][50] += 2.0  # y runs from -1.9 to 1.9, smoothly
        before = glitched["y"].copy()
        model = sidc.compile(self.model_path)
        result = model.fit(glitched, no_validate=True)
        found = result.document["outliers"]
        self.assertEqual([(s["signal"], [x["sample"] for x in s["samples"]]) for s in found], [("y", [50])])
        np.testing.assert_array_equal(glitched["y"], before)  # the caller's array is never written
        # The CLI on the same record in a file: the same outliers and estimates.
        path = os.path.join(self.dir, "glitched.csv")
        np.savetxt(path, np.column_stack([glitched[n] for n in ("t", "y", "ydot", "yddot", "x")]), delimiter=",",
                   header="t,y,ydot,yddot,x", comments="", fmt="%.17g")
        cli = json.loads(self.cli_fit("--no-validate", "--data", path))
        self.assertEqual(cli["outliers"][0]["samples"], found[0]["samples"])
        self.assertEstimatesEqual(result.estimates, json.dumps(cli))
        kept = model.fit(glitched, no_validate=True, keep_outliers=True)
        self.assertIsNone(kept.document["outliers"])
        self.assertNotEqual(kept.estimates, result.estimates)
        self.assertEqual(model.fit(record, no_validate=True).document["outliers"], [])

    def test_split_at_gaps_is_the_clis(self):
        # Appendix A with its row at t = 0.5 lost: refused whole, fitted as two stretches.
        lines = open(self.csv).read().splitlines(keepends=True)
        path = os.path.join(self.dir, "lost_row.csv")
        with open(path, "w") as f:
            f.writelines(line for line in lines if not line.startswith("0.50,"))
        model = sidc.compile(self.model_path)
        with self.assertRaises(sidc.ModelError) as caught:
            model.fit(path, no_validate=True)
        self.assertEqual(caught.exception.code, "data-time-step-not-uniform")
        result = model.fit(path, no_validate=True, split_at_gaps=True)
        cli = self.cli_fit("--no-validate", "--split-at-gaps", "--data", path)
        self.assertEstimatesEqual(result.estimates, cli)
        self.assertIn("split at its gaps into 2 stretches", result.report())

    def test_several_records(self):
        half = os.path.join(self.dir, "second.csv")
        record = read_record(self.csv)
        scaled = {k: (v if k == "t" else 1.0 * v) for k, v in record.items()}
        with open(self.csv) as src, open(half, "w") as dst:
            dst.write(src.read())
        cli = self.cli_fit("--data", self.csv, "--data", half, "--no-validate")
        result = sidc.compile(self.model_path).fit([self.csv, scaled], no_validate=True)
        self.assertIn("C1@2", result.estimates)
        self.assertEstimatesEqual(result.estimates, cli)

    def test_save_writes_what_the_cli_writes(self):
        result = sidc.compile(self.model_path).fit()
        out = os.path.join(self.dir, "saved")
        written = result.save(out=out)
        self.assertEqual(sorted(os.path.basename(p) for p in written), ["fit.json", "residuals.csv", "validation.csv"])
        with open(os.path.join(out, "fit.json")) as f:
            self.assertEqual(f.read(), result.to_json())
        self.assertEqual(result.to_json(), self.cli_fit())
        with open(os.path.join(out, "residuals.csv")) as f, open(os.path.join(self.dir, "out", "residuals.csv")) as g:
            self.assertEqual(f.read(), g.read())
        if shutil.which("gnuplot"):
            page = os.path.join(self.dir, "fit.html")
            drawn = result.save(plots=os.path.join(self.dir, "plots"), report=page)
            self.assertIn(page, drawn)
            self.assertTrue(any(p.endswith(".svg") for p in drawn))
            with open(page) as f:
                self.assertIn("quasi_linear", f.read())
        # An output that is an input is refused, and the record is left as it was.
        with open(self.csv) as f:
            before = f.read()
        with self.assertRaises(sidc.ModelError) as caught:
            result.save(report=self.csv)
        self.assertIn("an input of this run: writing it would destroy it", str(caught.exception))
        with open(self.csv) as f:
            self.assertEqual(f.read(), before)
        with self.assertRaises(TypeError):
            result.save()

    def test_local_fits_are_the_clis_local_csv(self):
        # Issue 18: local fits from the module give local.csv's columns, and save() writes the CLI's file.
        result = sidc.compile(self.model_path).fit(local=0.3, stride=3, no_validate=True)
        local = result.local
        self.assertIsNotNone(local)
        out = os.path.join(self.dir, "out")
        done = run_cli("fit", self.model_path, "--no-validate", "--local", "0.3", "--stride", "3", "--out", out)
        self.assertEqual(done.returncode, 0, done.stderr)
        with open(os.path.join(out, "local.csv")) as f:
            header = f.readline().strip().split(",")
        cli = np.genfromtxt(os.path.join(out, "local.csv"), delimiter=",", skip_header=1)
        self.assertEqual(list(local), header)
        for k, name in enumerate(header):  # empty cells (no estimate) read as NaN, as the module gives them
            np.testing.assert_array_equal(local[name], cli[:, k], err_msg=name)
        saved = os.path.join(self.dir, "saved")
        result.save(out=saved)
        with open(os.path.join(saved, "local.csv")) as f, open(os.path.join(out, "local.csv")) as g:
            self.assertEqual(f.read(), g.read())
        self.assertIsNone(sidc.compile(self.model_path).fit(no_validate=True).local)
        with self.assertRaises(ValueError):
            sidc.compile(self.model_path).fit(forget=1.0)

    def test_model_text(self):
        with open(self.model_path) as f:
            text = f.read().replace('"appendix_a.csv"', '"%s"' % self.csv)
        model = sidc.compile(text)
        self.assertIn("int(x)", model.rewritten)
        self.assertIn("m", model.parameters)
        self.assertEqual(model.signals, {"x": "input", "y": "output"})
        self.assertEstimatesEqual(model.fit(no_validate=True).estimates, self.cli_fit("--no-validate"))


class NumpyInOut(Workspace):
    def test_float32_is_converted(self):
        record = read_record(self.csv)
        as32 = {k: v.astype(np.float32) for k, v in record.items()}
        back = {k: v.astype(np.float64) for k, v in as32.items()}
        model = sidc.compile(self.model_path)
        self.assertEqual(model.fit(as32, no_validate=True).estimates, model.fit(back, no_validate=True).estimates)

    def test_arrays_handed_back_are_not_copies(self):
        result = sidc.compile(self.model_path).fit(self.csv, no_validate=True)
        residuals = result.residuals["residual"]
        self.assertFalse(residuals.flags.owndata)  # numpy wraps the result's own memory
        self.assertIsNotNone(residuals.base)
        self.assertEqual(residuals.dtype, np.float64)

    def test_contiguous_float64_is_borrowed_not_copied(self):
        # The record borrows a contiguous float64 array (a reference held while the result lives);
        # a strided one and a float32 one are copied or converted, so nothing of theirs is held.
        record = {k: np.ascontiguousarray(v) for k, v in read_record(self.csv).items()}
        strided = read_record(self.csv)
        before = {k: sys.getrefcount(record[k]) for k in record}
        strided_before = {k: sys.getrefcount(strided[k]) for k in strided}
        model = sidc.compile(self.model_path)
        result = model.fit(record, no_validate=True)
        other = model.fit(strided, no_validate=True)
        # The columns the model reads (its x is a formula of t); the others are let go with the record.
        used = {"t", "y"}
        self.assertLess(used, set(record))
        for k in record:
            self.assertEqual(sys.getrefcount(record[k]), before[k] + (k in used), k)
            self.assertEqual(sys.getrefcount(strided[k]), strided_before[k], k)
        self.assertEqual(result.estimates, other.estimates)
        # residuals() evaluates the borrowed record again: the same numbers as the copied one's.
        np.testing.assert_array_equal(result.residuals["residual"], other.residuals["residual"])
        del result
        for k in record:
            self.assertEqual(sys.getrefcount(record[k]), before[k], k)

    def test_record_is_not_changed(self):
        record = {k: np.ascontiguousarray(v) for k, v in read_record(self.csv).items()}
        before = {k: v.copy() for k, v in record.items()}
        sidc.compile(self.model_path).fit(record, no_validate=True)
        for k in record:
            np.testing.assert_array_equal(record[k], before[k])

    def test_gil_is_released_during_a_fit(self):
        # A record of 2*10^5 samples of a first-order system: the fit takes long enough to see whether
        # another Python thread runs meanwhile (with the lock held, it would not run at all).
        n = 200_000
        t = np.arange(n) * 1e-3
        x = np.sin(t)
        y = np.sin(t) - np.cos(t)  # y' + y = 2 sin t ... a known truth is not the point here
        model = sidc.compile("model first\ninput x\noutput y\nparam a, b\nset form = integrated\na*y' + b*y = x\n")
        span = {}

        def fit():
            span["start"] = time.perf_counter()
            model.fit({"t": t, "x": x, "y": y}, no_validate=True)
            span["end"] = time.perf_counter()

        worker = threading.Thread(target=fit)
        ticks = []
        worker.start()
        while worker.is_alive():
            ticks.append(time.perf_counter())
        worker.join()
        duration = span["end"] - span["start"]
        inside = [s for s in ticks if span["start"] + 0.2 * duration < s < span["end"] - 0.2 * duration]
        self.assertGreater(duration, 0.02)
        self.assertGreater(len(inside), 100, f"{len(inside)} ticks of the main thread during a {duration:.3f} s fit")


class BadInput(Workspace):
    def test_arrays_of_different_lengths(self):
        record = read_record(self.csv)
        record["x"] = record["x"][:-1]
        with self.assertRaises(ValueError) as caught:
            sidc.compile(self.model_path).fit(record)
        self.assertIn("<arrays>: column `x` has 100 values, column `t` has 101", str(caught.exception))
        self.assertIn("hint:", str(caught.exception))

    def test_non_float_dtypes(self):
        model = sidc.compile(self.model_path)
        for dtype in (np.int64, np.bool_, np.complex128, object):
            record = read_record(self.csv)
            record["y"] = record["y"].astype(dtype)
            with self.assertRaises(TypeError) as caught:
                model.fit(record)
            self.assertIn("column `y` holds", str(caught.exception))
            self.assertIn("not floating-point numbers", str(caught.exception))
        with self.assertRaises(ValueError):
            model.fit({"t": np.zeros((3, 2))})
        with self.assertRaises(TypeError):
            model.fit(42)
        with self.assertRaises(TypeError):
            model.fit([])  # None, not an empty list, reads the model's data statements
        with self.assertRaises(ValueError) as caught:
            model.fit(self.csv, form="weak", integrate=1)
        self.assertIn("exclude each other", str(caught.exception))

    def test_nan_in_a_record(self):
        record = {k: np.ascontiguousarray(v) for k, v in read_record(self.csv).items()}
        record["y"][17] = np.nan
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.compile(self.model_path).fit(record)
        e = caught.exception
        self.assertEqual((e.file, e.line, e.column, e.code), ("<arrays>", 17, 2, "data-nan-cell"))
        self.assertEqual(e.message, "cell in column `y` is NaN")
        self.assertTrue(str(e).startswith("<arrays>:17:2: error: cell in column `y` is NaN\nhint: "))
        # The same hole in a CSV: the CLI's message, the same words.
        with open(self.csv) as f:
            lines = f.read().splitlines()
        cells = lines[18].split(",")
        cells[1] = "nan"
        lines[18] = ",".join(cells)
        with open(self.csv, "w") as f:
            f.write("\n".join(lines) + "\n")
        done = run_cli("fit", self.model_path)
        self.assertIn("error: cell `nan` in column `y` is NaN", done.stderr)
        self.assertIn(e.hint, done.stderr)

    def test_unknown_keyword(self):
        model = sidc.compile(self.model_path)
        with self.assertRaises(TypeError) as caught:
            model.fit(self.csv, evry=2)
        self.assertIn("`fit()` has no setting `evry`", str(caught.exception))
        self.assertIn("did you mean `every`?", str(caught.exception))
        with self.assertRaises(ValueError) as caught:
            model.fit(self.csv, edges="cut")
        self.assertIn("`edges=cut` is not one of drop, shorten", str(caught.exception))
        with self.assertRaises(TypeError):
            model.fit(self.csv, every="2")
        with self.assertRaises(ValueError):
            model.fit(self.csv, every=0)
        with self.assertRaises(sidc.ModelError) as caught:
            model.fit(self.csv, derivative="savgol(7)")
        self.assertIn("is not a moving-arc operator", str(caught.exception))
        with self.assertRaises(TypeError) as caught:
            sidc.select(model, self.csv, rulz="aic")
        self.assertIn("did you mean `rule`?", str(caught.exception))

    def test_model_error_is_the_clis_text(self):
        path = os.path.join(self.dir, "broken.sid")
        with open(path, "w") as f:
            f.write("model broken\ninput x\noutput y\nparam a, b\na*y' + b*yy = x\n")
        done = run_cli("compile", path)
        self.assertEqual(done.returncode, 1)
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.compile(path)
        e = caught.exception
        self.assertEqual(str(e) + "\n", done.stderr)
        self.assertEqual((e.file, e.line, e.column), (path, 5, 10))
        self.assertIn("`yy`", e.message)
        self.assertEqual(e.hint, "did you mean `y`?")
        self.assertIsInstance(e, ValueError)

    def test_missing_file(self):
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.compile(os.path.join(self.dir, "none.sid"))
        self.assertIn("none.sid", str(caught.exception))
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.compile(self.model_path).fit(os.path.join(self.dir, "none.csv"))
        self.assertIn("none.csv", str(caught.exception))


class SelectAndSimulate(Workspace):
    def test_select_table_is_the_clis(self):
        model_path = os.path.join(self.dir, "select_sixth.sid")
        out = os.path.join(self.dir, "select")
        done = run_cli("select", model_path, "--out", out, "--folds", "0")
        self.assertEqual(done.returncode, 0, done.stderr)
        with open(os.path.join(out, "select.json")) as f:
            cli = json.load(f)
        table = sidc.select(sidc.compile(model_path), folds=0)
        rows = [row for g in cli["groups"] for row in g["sizes"]]
        self.assertEqual(len(table), len(rows))
        for mine, theirs in zip(table, rows):
            self.assertEqual(mine["size"], theirs["size"])
            self.assertEqual(mine["G"], theirs["G"])
            self.assertEqual(mine["parameters"], theirs["parameters"])
        chosen = [row["size"] for row in table if row["chosen"]]
        self.assertEqual(chosen, [cli["groups"][0]["chosen_size"]])
        seconds = re.compile(r"\d+\.\d+ s\b")  # the search's own timing
        self.assertEqual(seconds.sub("s", table.report()), seconds.sub("s", done.stdout))

    def test_simulate_is_the_clis(self):
        path = os.path.join(self.dir, "oscillator.sid")
        with open(path, "w") as f:
            f.write("model oscillator\ninput u = sin(t)\noutput y\nparam a, b\ny'' + a*y' + b*y = u\n")
        done = run_cli("simulate", path, "--param", "a=0.5", "--param", "b=4", "--initial", "y=1", "--t1", "5", "--step", "0.01")
        self.assertEqual(done.returncode, 0, done.stderr)
        cli = np.genfromtxt(done.stdout.splitlines(), delimiter=",", names=True)
        t = np.arange(501) * 0.01
        out = sidc.simulate(sidc.compile(path), {"a": 0.5, "b": 4}, None, t, {"y": 1.0})
        np.testing.assert_array_equal(out["t"], cli["t"])
        np.testing.assert_allclose(out["y"], cli["y"], rtol=1e-12, atol=1e-12)
        self.assertFalse(out["y"].flags.owndata)

    def test_simulate_bad_input(self):
        model = sidc.compile(os.path.join(self.dir, "system_4_1_1.sid"))
        t = np.arange(11) * 0.1
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.simulate(model, {"m": 1.0}, None, t)
        self.assertIn("c_minus", str(caught.exception))
        with self.assertRaises(sidc.ModelError) as caught:
            sidc.simulate(model, {"mass": 1.0}, None, t)
        self.assertIn("mass", str(caught.exception))
        with self.assertRaises(TypeError):
            sidc.simulate(model, {"m": 1.0}, None, t.astype(int))
        with self.assertRaises(ValueError) as caught:
            sidc.simulate(model, {"m": float("nan")}, None, t)
        self.assertIn("`m` is nan, not a finite number", str(caught.exception))


if __name__ == "__main__":
    unittest.main()
