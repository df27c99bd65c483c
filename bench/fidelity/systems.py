"""The known-truth systems of the fidelity benchmark (issue 13, item 7).

Each system gives: its equations as a sidc model with the true terms (every parameter free, one
term with a known coefficient, as sidc requires), the true parameter values, a candidate library
for `sidc select` (the true terms and about as many plausible wrong ones) with the names of the
true candidates, the sampling (step, samples), the input signals (smooth multisines: several
incommensurate frequencies, so the record excites the dynamics over a band), the initial state and
the right-hand side that `integrate.py` solves. Sampling: tens of samples or more per period of
the fastest input component and of the fastest mode, a few thousand samples.

One system, `process_held`, has its input held between samples (`input x held`): the input is a
sequence of levels, one per sample interval, drawn per seed (`held_input`), which the generator
keeps constant on each interval (integrate.rk4_held).
"""

import math
import random
from dataclasses import dataclass, field


def multisine(*components, offset=0.0):
    """x(t) = offset + sum a*sin(w*t + phi) over (a, w, phi)."""
    return lambda t: offset + sum(a * math.sin(w * t + p) for a, w, p in components)


@dataclass
class System:
    name: str
    title: str
    inputs: dict                 # input name -> function of t (None for an input in held_input)
    outputs: list                # output names (recorded, noisy)
    states: list                 # state names as `sidc simulate --initial` takes them ("y", "y'")
    output_state: dict           # output name -> index in the state vector
    x0: list                     # true initial state
    step: float
    samples: int
    substeps: int                # RK4 steps per sample interval in the generator
    truth: dict                  # parameter -> true value
    equations: str               # the true model's equations (sidc syntax)
    library: str                 # candidate equations for `sidc select`
    library_truth: dict          # equation index (1-based) -> set of true candidate names
    rhs: object = None           # f(t, state, inputs) -> state derivative
    sliding: object = None       # (accel, friction, torque) for Coulomb friction
    notes: str = ""
    smooth: bool = True          # False: guards or sign() (issue 13's 2% target instead of 0.05% / 0.3%)
    holds: dict = field(default_factory=dict)  # input name -> "held" / "linear" (`input x held`); absent: smooth
    issue13: bool = True         # one of the eight systems issue 13's error targets are counted over
    held_input: object = None    # f(seed) -> {input name: one value per sample, holding until the next}
    # Parameters that enter nonlinearly (`param L = 1.5` inside `sin(L*y)`): their guesses, which
    # the models declare; the library then declares its parameters too (library_params).
    guesses: dict = field(default_factory=dict)
    library_params: list = field(default_factory=list)
    # A chaotic system (> 0): no free run follows its record for long, however right the equations,
    # so the verdict's truth is the fitted equations run from the true state every this many time
    # units (run.py), and `rhs_with(parameters)` gives their right-hand side.
    chaotic_horizon: float = 0.0
    rhs_with: object = None


def _duffing():
    m, c, k, k3 = 1.0, 0.25, 1.0, 0.5
    x = multisine((1.5, 0.7, 0.0), (0.8, 1.9, 0.3), (0.4, 3.7, 0.0))
    return System(
        name="duffing", title="forced Duffing oscillator",
        inputs={"x": x}, outputs=["y"], states=["y", "y'"], output_state={"y": 0},
        x0=[0.0, 0.0], step=0.05, samples=3000, substeps=20,
        truth={"m": m, "c": c, "k": k, "k3": k3},
        equations="m*y'' + c*y' + k*y + k3*y^3 = x",
        library="m*y'' + c*y' + k*y + k3*y^3 + k2*y^2 + c3*y'^3 + d*y^2*y' + e*y*y' = x",
        library_truth={1: {"m", "c", "k", "k3"}},
        rhs=lambda t, s, u: [s[1], (u["x"] - c * s[1] - k * s[0] - k3 * s[0] ** 3) / m],
        notes="x = 1.5 sin 0.7t + 0.8 sin(1.9t + 0.3) + 0.4 sin 3.7t (as bench/fit_bench.cpp)")


def _van_der_pol():
    mu = 1.0
    return System(
        name="vanderpol", title="van der Pol oscillator (unforced, mu = 1)",
        inputs={}, outputs=["y"], states=["y", "y'"], output_state={"y": 0},
        x0=[0.2, 0.0], step=0.05, samples=2400, substeps=20,
        truth={"c1": -mu, "c2": mu, "k": 1.0},
        equations="y'' + c1*y' + c2*y^2*y' + k*y = 0",
        library="y'' + c1*y' + c2*y^2*y' + k*y + k2*y^2 + k3*y^3 + c3*y'^3 + e*y*y' = 0",
        library_truth={1: {"c1", "c2", "k"}},
        rhs=lambda t, s, u: [s[1], mu * (1 - s[0] ** 2) * s[1] - s[0]],
        notes="starts at y = 0.2 inside the limit cycle, so the record holds the growth onto it")


def _lotka_volterra():
    a, b, c, d = 1.0, 0.4, 0.8, 0.2
    return System(
        name="lotka", title="Lotka-Volterra (two outputs)",
        inputs={}, outputs=["u", "v"], states=["u", "v"], output_state={"u": 0, "v": 1},
        x0=[6.0, 2.0], step=0.05, samples=2000, substeps=20,
        truth={"a": a, "b": b, "c": c, "d": d},
        equations="u' = a*u - b*u*v\nv' = -c*v + d*u*v",
        library="u' = a*u - b*u*v + a2*u^2 + a3*v + a4\nv' = -c*v + d*u*v + c2*v^2 + c3*u + c4",
        library_truth={1: {"a", "b"}, 2: {"c", "d"}},
        rhs=lambda t, s, u: [a * s[0] - b * s[0] * s[1], -c * s[1] + d * s[0] * s[1]],
        notes="equilibrium u = 4, v = 2.5; the orbit through (6, 2)")


def _third_order():
    # (s + 1)(s^2 + s + 2.5) = s^3 + 2 s^2 + 3.5 s + 2.5, static gain 1
    a2, a1, a0, b0 = 2.0, 3.5, 2.5, 2.5
    x = multisine((1.0, 0.4, 0.0), (0.6, 1.1, 0.5), (0.4, 2.3, 1.0), (0.3, 3.9, 2.0))
    return System(
        name="linear3", title="third-order linear system",
        inputs={"x": x}, outputs=["y"], states=["y", "y'", "y''"], output_state={"y": 0},
        x0=[0.0, 0.0, 0.0], step=0.05, samples=3000, substeps=20,
        truth={"a2": a2, "a1": a1, "a0": a0, "b0": b0},
        equations="y''' + a2*y'' + a1*y' + a0*y = b0*x",
        library="y''' + a2*y'' + a1*y' + a0*y + q3*y^3 + q2*y*y' + e = b0*x + b1*x' + b2*x''",
        library_truth={1: {"a2", "a1", "a0", "b0"}},
        rhs=lambda t, s, u: [s[1], s[2], b0 * u["x"] - a0 * s[0] - a1 * s[1] - a2 * s[2]],
        notes="poles -1 and -0.5 +- 1.5i; x = sin 0.4t + 0.6 sin(1.1t + 0.5) + 0.4 sin(2.3t + 1) + 0.3 sin(3.9t + 2)")


def _piecewise():
    m, cm, cp, km, kp = 1.0, 0.3, 0.8, 1.0, 3.0
    x = multisine((2.0, 0.9, 0.0), (1.2, 2.3, 0.7), (0.6, 4.1, 1.3))

    def rhs(t, s, u):
        y, v = s
        damper = cm * v if v <= 0 else cp * v
        spring = km * y if y <= 0 else kp * y
        return [v, (u["x"] - damper - spring) / m]

    return System(
        name="piecewise", title="piecewise damper and spring (as eq. 4-1.8)",
        inputs={"x": x}, outputs=["y"], states=["y", "y'"], output_state={"y": 0},
        x0=[0.0, 0.0], step=0.04, samples=3000, substeps=25,
        truth={"m": m, "cm": cm, "cp": cp, "km": km, "kp": kp},
        equations="m*y'' + cm*y'*[y' <= 0] + cp*y'*[y' > 0] + km*y*[y <= 0] + kp*y*[y > 0] = x",
        library=("m*y'' + cm*y'*[y' <= 0] + cp*y'*[y' > 0] + km*y*[y <= 0] + kp*y*[y > 0] +\n"
                 "    cm3*y'^3*[y' <= 0] + cp3*y'^3*[y' > 0] + km3*y^3*[y <= 0] + kp3*y^3*[y > 0] + k2*y^2 = x"),
        library_truth={1: {"m", "cm", "cp", "km", "kp"}},
        rhs=rhs, smooth=False,
        notes="damper 0.3 y' (y' <= 0) / 0.8 y' (y' > 0), spring 1.0 y (y <= 0) / 3.0 y (y > 0): "
              "forces continuous at the switches, slopes not")


def _stiff():
    a1, a2, b1, a3, a4, c1 = 50.0, 10.0, 50.0, 0.5, 0.3, 1.0
    x = multisine((1.0, 0.6, 0.0), (0.5, 5.0, 1.0), (0.3, 40.0, 0.5))
    return System(
        name="stiff", title="stiff slow-fast system (time constants 0.02 and 2)",
        inputs={"x": x}, outputs=["y1", "y2"], states=["y1", "y2"], output_state={"y1": 0, "y2": 1},
        x0=[0.0, 0.0], step=0.002, samples=5000, substeps=20,
        truth={"a1": a1, "a2": a2, "b1": b1, "a3": a3, "a4": a4, "c1": c1},
        equations="y1' + a1*y1 + a2*y2 = b1*x\ny2' + a3*y2 + a4*y2^3 = c1*y1",
        library=("y1' + a1*y1 + a2*y2 + p1*y1^2 + p2*y2^2 + p3*y1*y2 = b1*x\n"
                 "y2' + a3*y2 + a4*y2^3 + q1*y2^2 + q2*x + q3*y1*y2 = c1*y1"),
        library_truth={1: {"a1", "a2", "b1"}, 2: {"a3", "a4", "c1"}},
        rhs=lambda t, s, u: [b1 * u["x"] - a1 * s[0] - a2 * s[1], c1 * s[0] - a3 * s[1] - a4 * s[1] ** 3],
        notes="fast mode 1/50, slow mode about 2; x = sin 0.6t + 0.5 sin(5t + 1) + 0.3 sin(40t + 0.5)")


# thesis eq. 4-2.5 (time in minutes): the process of `process` and `process_held`
PROCESS_TRUTH = {"a1": -0.169520, "a2": -0.150604, "a3": -0.013276, "a4": 7.607216,
                 "a5": -0.166036, "a6": -0.170566, "a7": -0.001100, "a8": 8.578805}
PROCESS_MODEL = dict(
    outputs=["y1", "y2"], states=["y1", "y2"], output_state={"y1": 0, "y2": 1}, x0=[0.0, 50.0],
    truth=PROCESS_TRUTH,
    equations="y1' = a1*y1 + a2*y2 + a3*x + a4\ny2' = a5*y1 + a6*y2 + a7*x + a8",
    library=("y1' = a1*y1 + a2*y2 + a3*x + a4 + p1*y1^2 + p2*y1*y2 + p3*y1*x + p4*x'\n"
             "y2' = a5*y1 + a6*y2 + a7*x + a8 + q1*y1^2 + q2*y1*y2 + q3*y1*x + q4*x'"),
    library_truth={1: {"a1", "a2", "a3", "a4"}, 2: {"a5", "a6", "a7", "a8"}},
    rhs=lambda t, s, u: [PROCESS_TRUTH["a1"] * s[0] + PROCESS_TRUTH["a2"] * s[1] + PROCESS_TRUTH["a3"] * u["x"] + PROCESS_TRUTH["a4"],
                         PROCESS_TRUTH["a5"] * s[0] + PROCESS_TRUTH["a6"] * s[1] + PROCESS_TRUTH["a7"] * u["x"] + PROCESS_TRUTH["a8"]],
)


def _process():
    x = multisine((30.0, 0.25, 0.0), (15.0, 0.07, 1.0), (10.0, 0.6, 2.0), offset=100.0)
    return System(
        name="process", title="two-output process (thesis eq. 4-2.5, smooth input)",
        inputs={"x": x}, step=0.1, samples=3000, substeps=10, **PROCESS_MODEL,
        notes="x = 100 + 30 sin 0.25t + 15 sin(0.07t + 1) + 10 sin(0.6t + 2); y1(0) = 0, y2(0) = 50")


def held_steps(rng, samples, low, high, longest):
    """One value per sample interval: a level drawn uniformly in [low, high], held for 1 to
    `longest` intervals (equally likely), then a new level; as a test engineer applies steps."""
    values = []
    while len(values) < samples:
        level = rng.uniform(low, high)
        values.extend([level] * min(rng.randint(1, longest), samples - len(values)))
    return values


def _process_held():
    # thesis eq. 4-2.5 as _process, with the input held between samples (thesis section 4-2: the
    # plant's input was set and held, not swept); sampled as the thesis' record, every 0.75 min.
    samples = 115  # 0 to 85.5 min
    return System(
        name="process_held", title="two-output process (thesis eq. 4-2.5, input held between samples)",
        inputs={"x": None}, step=0.75, samples=samples, substeps=15, **PROCESS_MODEL,
        holds={"x": "held"}, issue13=False,
        held_input=lambda seed: {"x": held_steps(random.Random(f"process_held/input/{seed}"), samples, 70.0, 130.0, 4)},
        notes="x held between samples: levels uniform in [70, 130], each for 1 to 4 intervals of 0.75 min, "
              "drawn by random.Random('process_held/input/SEED'); y1(0) = 0, y2(0) = 50")


def _pendulum():
    J, c, f, k = 0.5, 0.1, 0.2, 2.0
    x = multisine((0.5, 1.7, 0.0), (0.4, 0.6, 0.4), (0.3, 3.1, 1.1))
    torque = lambda t, y, v: x(t) - c * v - k * math.sin(y)
    accel = lambda t, y, v, mode: (torque(t, y, v) - f * mode) / J
    return System(
        name="pendulum", title="pendulum with viscous and Coulomb friction",
        inputs={"x": x}, outputs=["y"], states=["y", "y'"], output_state={"y": 0},
        x0=[0.0, 0.0], step=0.02, samples=4000, substeps=20,
        truth={"J": J, "c": c, "f": f, "k": k},
        equations="J*y'' + c*y' + f*sign(y') + k*sin(y) = x",
        library=("J*y'' + c*y' + f*sign(y') + k*sin(y) + k1*y + k3*y^3 + q*y'^2*sign(y') +\n"
                 "    c3*y'^3 = x"),
        library_truth={1: {"J", "c", "f", "k"}},
        sliding=(accel, f, torque), smooth=False,
        notes="y is the angle; x the applied torque 0.5 sin 1.7t + 0.4 sin(0.6t + 0.4) + 0.3 sin(3.1t + 1.1); "
              "swings within +-1.3 rad; 43 velocity reversals located, never stuck (sticking is handled)")


def _pendulum_length():
    J, c, mgl, L = 1.0, 0.3, 9.81, 0.8
    u = multisine((2.0, 0.7, 0.0), (1.5, 1.9, 0.0))
    return System(
        name="pendulum_length", title="driven pendulum with a parameter inside its restoring term",
        inputs={"u": u}, outputs=["y"], states=["y", "y'"], output_state={"y": 0},
        x0=[0.5, 0.0], step=0.01, samples=4000, substeps=10,
        truth={"J": J, "c": c, "mgl": mgl, "L": L},
        equations="J*y'' + c*y' + mgl*sin(L*y) = u",
        # No k*y or k*y^3 among the candidates: sin(L*y) approaches them as L goes to 0, and then
        # nothing determines L (variable projection says so, docs/cli.md).
        library="J*y'' + c*y' + mgl*sin(L*y) + k2*y^2 + d*y*y' + c3*y'^3 + q*y'^2*y = u",
        library_truth={1: {"J", "c", "mgl"}},
        rhs=lambda t, s, x: [s[1], (x["u"] - c * s[1] - mgl * math.sin(L * s[0])) / J],
        guesses={"L": 1.5}, library_params=["J", "c", "mgl", "k2", "d", "c3", "q", "L"],
        issue13=False,
        notes="issue 15, item 2: L enters nonlinearly (guess 1.5); the fit holds it at the value of least "
              "equation error (variable projection), `set refine = simulation` estimates it with the others")


def _lorenz():
    sigma, rho, beta = 10.0, 28.0, 8.0 / 3.0

    def rhs_with(p):
        return lambda t, s, u: [p["a"] * s[1] + p["b"] * s[0], p["r"] * s[0] + p["c"] * s[0] * s[2] + p["d"] * s[1],
                                p["e"] * s[0] * s[1] + p["g"] * s[2]]

    truth = {"a": sigma, "b": -sigma, "r": rho, "c": -1.0, "d": -1.0, "e": 1.0, "g": -beta}
    quadratic = "{0}1*x + {0}2*y + {0}3*z + {0}4*x*y + {0}5*x*z + {0}6*y*z + {0}7*x^2 + {0}8*y^2 + {0}9*z^2 + {0}0"
    return System(
        name="lorenz", title="Lorenz system (chaotic, three outputs)",
        inputs={}, outputs=["x", "y", "z"], states=["x", "y", "z"], output_state={"x": 0, "y": 1, "z": 2},
        x0=[-8.0, 7.0, 27.0], step=0.01, samples=5000, substeps=20,
        truth=truth,
        equations="x' = a*y + b*x\ny' = r*x + c*x*z + d*y\nz' = e*x*y + g*z",
        # The quadratic library of equation discovery (SINDy's Lorenz example), the true terms named
        # by the true parameters and left out of the p/q/w series.
        library="x' = " + quadratic.format("p").replace("p1*x", "b*x").replace("p2*y", "a*y") + "\n"
                "y' = " + quadratic.format("q").replace("q1*x", "r*x").replace("q2*y", "d*y").replace("q5*x*z", "c*x*z") + "\n"
                "z' = " + quadratic.format("w").replace("w3*z", "g*z").replace("w4*x*y", "e*x*y"),
        library_truth={1: {"a", "b"}, 2: {"r", "c", "d"}, 3: {"e", "g"}},
        rhs=rhs_with(truth), issue13=False, chaotic_horizon=2.0, rhs_with=rhs_with,
        notes="sigma 10, rho 28, beta 8/3 from (-8, 7, 27): 50 time units, about 65 oscillations of z; largest Lyapunov "
              "exponent about 0.9, so a free run departs after a few time units from any state known to within the noise")


SYSTEMS = [_duffing(), _van_der_pol(), _lotka_volterra(), _third_order(), _piecewise(), _stiff(),
           _process(), _pendulum(), _process_held(), _pendulum_length(), _lorenz()]
BY_NAME = {s.name: s for s in SYSTEMS}
