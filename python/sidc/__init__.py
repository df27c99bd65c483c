"""sidc from Python: compile a model, fit it to numpy arrays or CSV files, select, simulate.

The engine is the compiled `sidc._sidc` (python/module.cpp); this file is the face: `compile`,
`Model.fit`, `select`, `simulate`, the `FitResult` and `ModelError`. Settings are the command
line's options as keyword arguments (`sidc fit --every 2` is `m.fit(data, every=2)`; `--from` is
`from_=`), with the CLI's wording for every error. docs/python.md walks through it.

Relies on: `_sidc` beside this file. Guarantees: sidc's diagnostics raise `ModelError` (a
ValueError) whose str() is the text the CLI prints; what the CLI prints as warnings is issued with
`warnings.warn` (category `SidcWarning`); nothing is written to a file.
"""
import json
import math
import os
import warnings as _warnings

from . import _sidc

__all__ = ["compile", "select", "simulate", "Model", "FitResult", "SelectTable", "ModelError", "SidcWarning", "__version__"]
__version__ = _sidc.version


class SidcWarning(UserWarning):
    """What the CLI prints on stderr as a warning (a noisy signal, drift, a rank-deficient fit)."""


class ModelError(ValueError):
    """A problem with the model, a record or a setting, as the CLI reports it.

    str(): the CLI's framed text (every diagnostic, each `file:line:col: error: ...`, the source
    line with a caret, `hint: ...`). Fields of the first one: file, line, column (a data file's row
    and column; None when the message is about no place), message, hint, code. `diagnostics`: a
    dict of those fields for each one.
    """

    def __init__(self, text, diagnostics=()):
        super().__init__(text)
        self.text = text
        self.diagnostics = list(diagnostics)
        first = next((d for d in self.diagnostics if d["severity"] == "error"), self.diagnostics[0] if self.diagnostics else {})
        self.file = first.get("file")
        self.line = first.get("line")
        self.column = first.get("column")
        self.message = first.get("message", text)
        self.hint = first.get("hint")
        self.code = first.get("code")

    def __str__(self):
        return self.text


def _warn(texts):
    for text in texts:
        _warnings.warn(text, SidcWarning, stacklevel=3)


def _number(value):
    """fit.json writes non-finite numbers as "inf", "-inf", "nan"."""
    return float(value) if isinstance(value, str) else value


def _looks_like_path(text):
    return "\n" not in text and (os.path.exists(text) or text.endswith(".sid") or text.endswith(".sidc.json"))


def compile(model, name="<string>"):
    """A Model from a model file's path (`.sid` or `.sidc.json`) or from model text.

    Text is told from a path by having a line break or not naming a file; `name` is the text's name
    in messages, and relative data statements of text are read from the current folder.
    """
    if isinstance(model, os.PathLike):
        model = os.fspath(model)
    if not isinstance(model, str):
        raise TypeError(f"compile() takes a model's text or its path, not {type(model).__name__}")
    handle, said = _sidc.compile_file(model) if _looks_like_path(model) else _sidc.compile_text(model, name)
    _warn(said)
    return Model(handle)


class Model:
    """A compiled model. `rewritten`: its equations as fitted (the integrated form, as `sidc compile`
    prints it); `normalized`: the derivative form; `parameters`: the names `simulate` needs;
    `signals`: name -> "input" or "output"."""

    def __init__(self, handle):
        self._handle = handle

    name = property(lambda self: self._handle.name)
    path = property(lambda self: self._handle.path)
    rewritten = property(lambda self: self._handle.rewritten)
    normalized = property(lambda self: self._handle.normalized)
    parameters = property(lambda self: self._handle.parameters)
    signals = property(lambda self: self._handle.signals)

    def fit(self, data=None, **settings):
        """Fit to `data`: a CSV path, a dict of 1-D arrays (named like CSV columns; `t` is time), a
        list of either (several records), or None for the model's data statements. `settings`: the
        options of `sidc fit` (from_, to, every, step, resample, derivative, second_derivative,
        edges, integration, precision, weights, split_at_gaps, keep_outliers, integrate, form, no_validate, validate,
        validate_samples, refine_samples, refine_segments, initial_state, refine, no_noise_check, estimator, local,
        stride, forget)."""
        return FitResult(_sidc.fit(self._handle, data, settings))

    def __repr__(self):
        return f"<sidc.Model {self.name!r} from {self.path}>"


class FitResult:
    """One fit. `estimates`, `standard_errors`, `ci95`: dicts by parameter name (integration
    constants too, as fit.json lists them); `hac_ci95`: the Newey-West intervals where computed;
    `nonlinear`: the parameters that enter nonlinearly (held values, standard errors, refined); `covariance`: a numpy matrix in the order of
    `estimates`; `G`: the sum of squared equation errors over the groups (eq. 2-1.7);
    `statistics`: one dict per equation group (fit.json's); `validation`: fit.json's (None with
    no_validate); `residuals`: dict of numpy arrays (residuals.csv's columns); `report()`: what
    `sidc fit` prints; `to_json()`: fit.json's text."""

    def __init__(self, handle):
        self._handle = handle
        self._json_text = None
        self._document = None
        self._residuals = None
        self._covariance = None
        _warn(handle.warnings)

    def to_json(self):
        if self._json_text is None:
            self._json_text = self._handle.json()
        return self._json_text

    @property
    def document(self):
        """fit.json as a dict."""
        if self._document is None:
            self._document = json.loads(self.to_json())
        return self._document

    def report(self):
        return self._handle.report()

    def save(self, out=None, plots=None, report=None):
        """Write what `sidc fit --out OUT --plots PLOTS --report REPORT` writes: fit.json,
        residuals.csv and validation.csv into the folder `out`, the pictures (SVG and PNG, drawn
        by gnuplot) into the folder `plots`, the one-page HTML report to the file `report`; each
        only when given. Returns the paths written. Files are replaced atomically; an output that
        is one of the fit's inputs is refused (sidc.ModelError), as the CLI refuses it."""
        if out is None and plots is None and report is None:
            raise TypeError("save() needs at least one of out, plots, report")
        paths = [os.fspath(p) if p is not None else "" for p in (out, plots, report)]
        return self._handle.save(*paths)

    @property
    def local(self):
        """The local fits (`local=WIDTH` or `forget=LAMBDA`, or the model's `set local`; thesis
        chapter V) as a dict of numpy arrays named like local.csv's columns (t_center, each
        parameter, its `_se`, G, n, rank; NaN where a window has no estimate); None without them."""
        return self._handle.local()

    @property
    def usable(self):
        return self._handle.usable

    def _parameters(self):
        return [p for g in self.document["groups"] for p in g["parameters"]]

    @property
    def estimates(self):
        return {p["name"]: _number(p["estimate"]) for p in self._parameters()}

    @property
    def standard_errors(self):
        return {p["name"]: _number(p["standard_error"]) for p in self._parameters()}

    @property
    def ci95(self):
        return {p["name"]: tuple(_number(x) for x in p["ci95"]) for p in self._parameters()}

    @property
    def hac_ci95(self):
        """The Newey-West (HAC) 95% intervals, which allow for autocorrelated rows, by parameter name,
        where the fit computed them (dense derivative- and integrated-form fits: docs/accuracy.md,
        "Intervals under autocorrelated rows"); the residual analysis says which intervals to trust."""
        return {p["name"]: tuple(_number(x) for x in p["hac_ci95"]) for p in self._parameters() if "hac_ci95" in p}

    @property
    def nonlinear(self):
        """The parameters that enter nonlinearly (`param L = 1.2` inside `sin(L*theta)`), by name:
        dicts with `guess`, `held` (the value the equation-error fit held it at, found by variable
        projection), `standard_error` and `ci95` (held -/+ 1.96 standard errors; None without a
        standard error) and, after a refinement that did not fail, `refined`; {} when there are none.
        `estimates` and the others list only the parameters the linear fit estimated."""
        block = self.document.get("nonlinear_parameters") or {}
        out = {}
        for p in block.get("parameters", []):
            se = _number(p["standard_error"]) if p.get("standard_error") is not None else None
            held = _number(p["held"])
            out[p["name"]] = {"guess": _number(p["guess"]), "held": held, "standard_error": se,
                              "ci95": (held - 1.96 * se, held + 1.96 * se) if se is not None else None}
        refinement = self.document.get("refinement") or {}
        if refinement.get("status") not in (None, "failed"):
            for p in refinement.get("parameters", []):
                if p["name"] in out:
                    out[p["name"]]["refined"] = _number(p["refined"])
        return out

    @property
    def covariance(self):
        if self._covariance is None:
            self._covariance = self._handle.covariance()[1]
        return self._covariance

    @property
    def G(self):
        return math.fsum(_number(g["statistics"]["G"]) for g in self.document["groups"])

    @property
    def statistics(self):
        return [{k: _number(v) for k, v in g["statistics"].items()} for g in self.document["groups"]]

    @property
    def validation(self):
        return self.document.get("validation")

    @property
    def residuals(self):
        if self._residuals is None:
            self._residuals = self._handle.residuals()
        return self._residuals

    def __repr__(self):
        return "<sidc.FitResult " + ", ".join(f"{k}={v:.6g}" for k, v in self.estimates.items()) + ">"


class SelectTable(list):
    """The best subset of every size, one dict per row (select.json's `sizes`, with `group` and
    `chosen`); `report()`: what `sidc select` prints; `to_json()`: select.json's text."""

    def __init__(self, document, report):
        self._text = document
        self._report = report
        rows = []
        for index, group in enumerate(json.loads(document)["groups"], start=1):
            for row in group["sizes"]:
                row = {k: _number(v) if k != "parameters" else {n: _number(x) for n, x in v.items()} for k, v in row.items()}
                rows.append({"group": index, **row, "chosen": row["size"] == group["chosen_size"]})
        super().__init__(rows)

    def report(self):
        return self._report

    def to_json(self):
        return self._text


def select(model, data=None, **settings):
    """Best subsets of `model`'s candidate operations (`sidc select`): a SelectTable. `settings`: the
    record settings of fit and method, rule, require, drop, group ({name: [parameters]}), folds,
    bootstrap, seed, max_size, simulate, simulate_samples, keep_drift."""
    document, report, said = _sidc.select(model._handle, data, settings)
    _warn(said)
    return SelectTable(document, report)


def simulate(model, params, inputs=None, t=None, initial=None, **settings):
    """Solve `model`'s equations with `params` ({name: value}, every parameter) on the time grid `t`,
    the inputs ({name: array on t}) and the initial state ({"y": 1.0, "y'": 0.0}; 0 for what is not
    given). settings: method ("rk4" or "adaptive"), stepper, substeps, tolerance. A dict of numpy
    arrays: `t` and each output. A run that diverges warns and has NaN after the stop."""
    if t is None:
        raise TypeError("simulate() needs the time grid `t`, a 1-D array")
    out, _, stopped = _sidc.simulate(model._handle, dict(params), inputs, t, initial, settings)
    if stopped:
        _warn([stopped])
    return out
