#!/usr/bin/env python3
"""Pictures name their record, a held-out record is marked everywhere, and a plots folder holds
only the current run's pictures (docs/pictures.md).

Fits the golden case fit/validate_other_record (train.csv fitted, check.csv given with
--validate) with --plots, --report and --out, then checks: each validation figure's SVG title
names its record, the held-out one as held out; fit.json's validation marks it `held_out`; the
report marks it; stdout heads its section as held out. Then plants, in the plots folder, a
picture an earlier run listed in the manifest and a user's own file, runs again, and checks the
first is gone and the second untouched.

Usage: pictures_test.py SIDC_BINARY SOURCE_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile


def run(cmd, cwd):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stdout}\n{r.stderr}")
    return r.stdout


def main():
    sidc, root = os.path.abspath(sys.argv[1]), sys.argv[2]
    case = os.path.join(root, "tests", "golden", "fit", "validate_other_record")
    with tempfile.TemporaryDirectory() as work:
        shutil.copy(case + ".sid", os.path.join(work, "model.sid"))
        for f in os.listdir(case + ".files"):
            shutil.copy(os.path.join(case + ".files", f), work)
        args = [sidc, "fit", "model.sid", "--validate", "check.csv", "--plots", "p", "--report", "r.html", "--out", "o"]
        stdout = run(args, work)
        assert "held-out record `check.csv` (--validate)" in stdout, "stdout does not mark check.csv as held out"
        svg = lambda name: open(os.path.join(work, "p", name + ".svg"), encoding="utf-8").read()
        assert "record train.csv" in svg("simulated_y_r1"), "the fitted record's figure does not name train.csv"
        assert "held-out record check.csv" in svg("simulated_y_r2"), "the held-out record's figure is not marked"
        assert "held-out record check.csv" in svg("error_y_r2")
        runs = json.load(open(os.path.join(work, "o", "fit.json")))["validation"]["records"]
        assert [r["held_out"] for r in runs] == [False, True], f"fit.json held_out: {[r['held_out'] for r in runs]}"
        report = open(os.path.join(work, "r.html"), encoding="utf-8").read()
        assert "check.csv (held out)" in report and "held-out record check.csv" in report, "the report does not mark check.csv"
        # Stale pictures: one listed by an earlier run goes, a user's own file stays.
        with open(os.path.join(work, "p", ".sidc-pictures"), "a") as manifest:
            manifest.write("simulated_z.svg\n")
        for name in ("simulated_z.svg", "my_notes.svg"):
            open(os.path.join(work, "p", name), "w").write("<svg/>")
        run(args, work)
        left = set(os.listdir(os.path.join(work, "p")))
        assert "simulated_z.svg" not in left, "a picture of an earlier run was left behind"
        assert "my_notes.svg" in left, "a file sidc did not write was removed"
        assert "simulated_y_r2.svg" in left
    print("pictures name their record; check.csv marked held out on stdout, in fit.json, pictures and report; stale picture removed, user file kept")
    return 0


if __name__ == "__main__":
    sys.exit(main())
