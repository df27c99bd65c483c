"""Known-truth records for the fidelity benchmark: the integrators that make them.

Classical fourth-order Runge-Kutta on a fixed step well below the sampling step (`substeps` steps
per sample interval). The accuracy of every record is checked by solving it again with half the
step (`halving_check`): the largest difference at the samples, relative to each output's standard
deviation, is printed by `records.py` and stated in README.md. Coulomb friction (a sign() of the
velocity) gets its own stepper, `rk4_sliding`, which locates each velocity reversal by bisection
and decides there between slipping on and sticking (a Filippov solution), so no step straddles a
change of the friction force. Inputs held between samples (`input x held`) get `rk4_held`, which
keeps each input constant on each sample interval. Pure Python, standard library only.
"""

import math


def rk4_step(f, t, s, h):
    k1 = f(t, s)
    k2 = f(t + h / 2, [a + h / 2 * b for a, b in zip(s, k1)])
    k3 = f(t + h / 2, [a + h / 2 * b for a, b in zip(s, k2)])
    k4 = f(t + h, [a + h * b for a, b in zip(s, k3)])
    return [a + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(s, k1, k2, k3, k4)]


def rk4(f, x0, step, samples, substeps):
    """States at t = k*step, k = 0..samples-1, by RK4 with `substeps` steps per sample interval."""
    h = step / substeps
    s = list(x0)
    out = [list(s)]
    for k in range(1, samples):
        t0 = (k - 1) * step
        for i in range(substeps):
            s = rk4_step(f, t0 + i * h, s, h)
        out.append(list(s))
    return out


def rk4_held(f, x0, step, samples, substeps, inputs):
    """As rk4, for inputs held between samples: f(t, s, u) with u = {name: value}, each input
    constant on each sample interval at the value it has at the interval's start (inputs: name ->
    one value per sample). The substeps stay inside the interval, so no RK4 step straddles a
    change of level and none evaluates an input at an instant where it jumps."""
    h = step / substeps
    s = list(x0)
    out = [list(s)]
    for k in range(1, samples):
        t0 = (k - 1) * step
        u = {name: values[k - 1] for name, values in inputs.items()}
        g = lambda t, state, u=u: f(t, state, u)
        for i in range(substeps):
            s = rk4_step(g, t0 + i * h, s, h)
        out.append(list(s))
    return out


def rk4_sliding(accel, friction, torque, x0, step, samples, substeps):
    """A second-order system J y'' = torque(t, y, y') - friction*sign(y'), as [y, y'] at the samples.

    accel(t, y, v, mode) is y'' with sign(y') replaced by `mode` (+1 or -1). At a velocity reversal
    (found by bisection to 1e-14 of the step) the velocity is set to 0 and the body slips on in the
    direction of the net force, or sticks while |torque(t, y, 0)| <= friction (thesis-style dry
    friction); a stuck body moves again where the net force first exceeds the friction (bisection
    too). `stuck_time` in the result is the total time spent stuck.
    """
    h = step / substeps
    y, v = x0
    mode = 1.0 if v > 0 else -1.0 if v < 0 else 0.0
    if mode == 0.0:
        mode = _new_mode(torque(0.0, y, 0.0), friction)
    stuck = 0.0
    out = [[y, v]]

    def slip(t, y, v, m, dt):
        f = lambda tt, s: [s[1], accel(tt, s[0], s[1], m)]
        return rk4_step(f, t, [y, v], dt)

    for k in range(1, samples):
        t = (k - 1) * step
        t_end = k * step
        while t < t_end - 1e-12 * step:
            dt = min(h, t_end - t)
            if mode == 0.0:
                # Stuck: y'' = 0 while the net force stays within the friction.
                if abs(torque(t + dt, y, 0.0)) <= friction:
                    stuck += dt
                    t += dt
                    continue
                lo, hi = 0.0, dt
                for _ in range(60):
                    mid = (lo + hi) / 2
                    if abs(torque(t + mid, y, 0.0)) <= friction:
                        lo = mid
                    else:
                        hi = mid
                stuck += hi
                t += hi
                mode = _new_mode(torque(t, y, 0.0), friction)
                continue
            y1, v1 = slip(t, y, v, mode, dt)
            if v1 * mode >= 0:
                y, v, t = y1, v1, t + dt
                continue
            # The velocity reverses inside this step: find where, stop there, decide what follows.
            lo, hi = 0.0, dt
            for _ in range(60):
                mid = (lo + hi) / 2
                if slip(t, y, v, mode, mid)[1] * mode > 0:
                    lo = mid
                else:
                    hi = mid
            y, _ = slip(t, y, v, mode, hi)
            v = 0.0
            t += hi
            mode = _new_mode(torque(t, y, 0.0), friction)
        out.append([y, v])
    return out, stuck


def _new_mode(net, friction):
    if net > friction:
        return 1.0
    if net < -friction:
        return -1.0
    return 0.0


def std(values):
    m = sum(values) / len(values)
    return math.sqrt(sum((a - m) ** 2 for a in values) / len(values))


def halving_check(solve, substeps, output_index):
    """Largest |difference| between the solutions with `substeps` and 2*`substeps`, relative to
    each output's standard deviation (the worst output)."""
    a = solve(substeps)
    b = solve(2 * substeps)
    worst = 0.0
    for j in output_index:
        sd = std([row[j] for row in b])
        diff = max(abs(p[j] - q[j]) for p, q in zip(a, b))
        worst = max(worst, diff / sd if sd > 0 else diff)
    return worst
