"""Known-truth records, models and candidate libraries of the fidelity benchmark, written to disk.

`noise_free(system)` solves a system (integrate.py) at its sampling step; `noisy(...)` adds
Gaussian noise of standard deviation level x (the standard deviation of each noise-free output
signal) to every output, with a generator seeded by the text "SYSTEM/LEVEL/SEED" (Python's
`random.Random` seeds a string through SHA-512, so records are the same on every machine and run).
Inputs stay noise-free. A system whose inputs are held between samples (`input x held`) draws its
input steps per seed, so its noise-free record depends on the seed too. `write_case(...)` writes
one case directory:

    record.csv      t, inputs, outputs (noisy)        the record sidc fits
    truth.csv       t, inputs, outputs (noise-free)   what "follows" is judged against
    model.sid       the true terms, parameters free   (data "record.csv")
    library.sid     candidate operations for `sidc select`
    truth.json      parameter values, initial state, noise, seed, generator check

Run as a script to write records for the tests (see tests/data/fidelity/README.md):

    python3 bench/fidelity/records.py --out DIR [--system NAME --noise LEVEL --seed S]...
"""

import argparse
import json
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import integrate  # noqa: E402
from systems import BY_NAME, SYSTEMS  # noqa: E402

SETTINGS_MARKER = "# settings (the benchmark inserts a configuration's `set` lines here)"


def held_inputs(system, seed):
    """The held inputs' values at the samples (each holding until the next sample), {} if none."""
    return system.held_input(seed) if system.held_input is not None else {}


def solve(system, substeps, seed=1):
    if system.sliding is not None:
        accel, friction, torque = system.sliding
        states, _ = integrate.rk4_sliding(accel, friction, torque, system.x0, system.step, system.samples, substeps)
        return states
    if system.held_input is not None:
        return integrate.rk4_held(system.rhs, system.x0, system.step, system.samples, substeps, held_inputs(system, seed))
    f = lambda t, s: system.rhs(t, s, {name: fn(t) for name, fn in system.inputs.items()})
    return integrate.rk4(f, system.x0, system.step, system.samples, substeps)


class Record:
    """A system's noise-free record. `seed` matters only for a system with held inputs, whose
    steps are drawn per seed; the others' records are the same for every seed."""

    def __init__(self, system, seed=1):
        self.system = system
        self.seed = seed
        self.states = solve(system, system.substeps, seed)
        self.t = [k * system.step for k in range(system.samples)]
        held = held_inputs(system, seed)
        self.inputs = {name: held[name] if name in held else [fn(t) for t in self.t] for name, fn in system.inputs.items()}
        self.outputs = {name: [row[i] for row in self.states] for name, i in system.output_state.items()}
        self.check = None
        self.stuck_time = None

    def verify(self):
        """Relative difference to the solution with half the step (the generator's accuracy)."""
        self.check = integrate.halving_check(lambda m: solve(self.system, m, self.seed), self.system.substeps,
                                             list(self.system.output_state.values()))
        return self.check


_CACHE = {}


def noise_free(system, seed=1):
    key = (system.name, seed if system.held_input is not None else None)
    if key not in _CACHE:
        _CACHE[key] = Record(system, seed)
    return _CACHE[key]


def noisy_outputs(record, level, seed, glitches=0):
    rng = random.Random(f"{record.system.name}/{level:g}/{seed}")
    out = {}
    for name, values in record.outputs.items():
        sigma = level * integrate.std(values)
        out[name] = [v + rng.gauss(0.0, sigma) for v in values] if sigma > 0 else list(values)
    for name, at in glitch_samples(record, level, seed, glitches).items():
        size = GLITCH_SHARE * integrate.std(record.outputs[name])
        glitch_rng = random.Random(f"{record.system.name}/{level:g}/{seed}/glitch-signs/{name}")
        for i in at:
            out[name][i] += size if glitch_rng.random() < 0.5 else -size
    return out


# `--glitches K`: K samples of each output put off by a fifth of its s.d. (a sensor glitch), at
# least 10 samples from the ends and from each other, drawn from their own stream.
GLITCH_SHARE = 0.2


def glitch_samples(record, level, seed, glitches):
    if glitches <= 0:
        return {}
    out = {}
    for name in record.outputs:
        rng = random.Random(f"{record.system.name}/{level:g}/{seed}/glitches/{name}")
        n, chosen = len(record.t), []
        while len(chosen) < glitches and n > 40:
            i = rng.randrange(10, n - 10)
            if all(abs(i - j) >= 10 for j in chosen):
                chosen.append(i)
        out[name] = sorted(chosen)
    return out


def csv_text(t, inputs, outputs):
    names = ["t"] + list(inputs) + list(outputs)
    cols = [t] + list(inputs.values()) + list(outputs.values())
    lines = [",".join(names)]
    for i in range(len(t)):
        lines.append(",".join(f"{c[i]:.15g}" for c in cols))
    return "\n".join(lines) + "\n"


def model_text(system, equations, kind, declare_params=True):
    lines = [f"# {system.title}: {kind} (bench/fidelity, generated by records.py)",
             f"model {system.name}_{'library' if kind.startswith('candidate') else 'true'}"]
    if system.inputs:
        lines.append("input " + ", ".join(f"{n} {system.holds[n]}" if n in system.holds else n for n in system.inputs))
    lines.append("output " + ", ".join(system.outputs))
    names = list(system.truth) if declare_params else list(system.library_params)
    if names:  # a nonlinear parameter needs its guess, so it needs a declaration
        lines.append("param " + ", ".join(f"{n} = {system.guesses[n]}" if n in system.guesses else n for n in names))
    lines.append('data "record.csv"')
    lines.append(SETTINGS_MARKER)
    lines.append(equations)
    return "\n".join(lines) + "\n"


def write_case(directory, system, level, seed, record=None, truth_csv=True, glitches=0):
    record = record or noise_free(system, seed)
    os.makedirs(directory, exist_ok=True)
    outputs = noisy_outputs(record, level, seed, glitches)
    files = {
        "record.csv": csv_text(record.t, record.inputs, outputs),
        "truth.csv": csv_text(record.t, record.inputs, record.outputs),
        "model.sid": model_text(system, system.equations, "the true terms, every parameter free"),
        "library.sid": model_text(system, system.library, "candidate operations for sidc select", declare_params=False),
    }
    truth = {
        "system": system.name, "title": system.title,
        "parameters": system.truth,
        "true_candidates": {str(k): sorted(v) for k, v in system.library_truth.items()},
        "initial_state": dict(zip(system.states, record.states[0])),
        "step": system.step, "samples": system.samples,
        "noise_level": level, "noise_seed": f"{system.name}/{level:g}/{seed}",
        "noise_sd": {name: level * integrate.std(v) for name, v in record.outputs.items()},
        "glitches": glitch_samples(record, level, seed, glitches),
        "inputs_noise_free": True,
        "generator": f"RK4, {system.substeps} steps per sample interval"
                     + (", velocity reversals located (Coulomb friction)" if system.sliding else "")
                     + (", held inputs constant on each sample interval" if system.held_input else ""),
        "notes": system.notes,
    }
    if system.holds:
        truth["inputs_held"] = dict(system.holds)  # each sample's value holds until the next sample
    if record.check is not None:
        truth["generator_halving_difference"] = record.check
    files["truth.json"] = json.dumps(truth, indent=2) + "\n"
    if not truth_csv:
        del files["truth.csv"]
    for name, text in files.items():
        with open(os.path.join(directory, name), "w") as f:
            f.write(text)
    return truth


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="directory; one sub-directory SYSTEM_NOISE_sSEED per record")
    p.add_argument("--system", action="append", help="system name (repeatable; default all)")
    p.add_argument("--noise", type=float, default=0.01, help="noise level (fraction of each output's s.d.)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--check", action="store_true", help="verify each record by halving the generator's step")
    p.add_argument("--no-truth-csv", action="store_true", help="leave out truth.csv (the noise-free record)")
    a = p.parse_args()
    for name in a.system or [s.name for s in SYSTEMS]:
        system = BY_NAME[name]
        record = noise_free(system, a.seed)
        if a.check:
            record.verify()
        d = os.path.join(a.out, f"{name}_noise{a.noise:g}_s{a.seed}")
        write_case(d, system, a.noise, a.seed, record, truth_csv=not a.no_truth_csv)
        amp = {k: (min(v), max(v)) for k, v in record.outputs.items()}
        print(f"{d}: {system.samples} samples, step {system.step}, outputs range "
              + ", ".join(f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in amp.items())
              + (f", halving difference {record.check:.2e} of the s.d." if record.check is not None else ""))


if __name__ == "__main__":
    main()
