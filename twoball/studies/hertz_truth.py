"""A slow, high-precision reference for the Hertz stack: mpmath Taylor series at 30 digits.

It shares no code with :mod:`twoball.kernels.hertz` or the DOP853 path of
:mod:`twoball.stacks.hertz`: only the model's inputs (the masses, each contact's Hunt-Crossley lam
and the heights at release, as :func:`inputs` takes them from the model's public functions),
converted exactly to mpmath numbers. The method is deliberately different (docs/model.md, "The Hertz
force"):

- **No singularity.** The force delta^(3/2) (1 + lam delta') is not smooth where a contact
  touches or releases (delta = 0). With rho_c = sqrt(delta_c) for each active contact and the
  time change dt = J dtau, J the product of the active contacts' rho, the equations become
  polynomial: dt/dtau = J, dx/dtau = J v, dv/dtau = J a(x, v) with the forces rho^3 (1 + lam
  delta'), drho_c/dtau = (J / rho_c) delta_c' / 2. Their solution is analytic in tau through a
  touch (rho starts at 0) and a release (rho falls through 0), so a Taylor series of any order
  converges there; free flight is the same equations with J = 1 (polynomials of degree two).
- **Taylor steps.** Each step computes the series of every variable to order :data:`ORDER` by
  the recurrences of the products (Cauchy products), and takes the step at which its last two
  terms are below :data:`TOLERANCE` relative (the rule of Jorba and Zou, 2005).
- **Events.** A contact becomes active when max(eta, lam eta' - 1) falls below zero (docs/model.md,
  "Bodies, coordinates, forces"), inactive when rho or 1 + lam delta' does; a ball in no active
  contact has an apex when its velocity falls through zero. Each is looked for at the end and at
  :data:`PROBES` points of each step, then refined by bisection on the series to ~1e-28.

Call :func:`solve_hertz_truth`. A two-ball drop takes seconds, four balls a minute or two.
Limit: a contact that closes with no speed (balls released touching) starts with rho = 0 and
rho' = 0, so J = 0 and the time change stalls; the reference does not handle it (the seeded drops
all have gaps).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from .stack_truth import difference_conditioning

DIGITS = 30
ORDER = 28
TOLERANCE = mpmath.mpf("1e-24")
PROBES = 8
MAX_STEP = 1e6  # tau, in free flight (where the series are polynomials)
MAX_STEPS = 200_000


@dataclass(frozen=True)
class HertzTruth:
    """Apexes (ball, t, height) and contact activations, as mpmath numbers."""

    apexes: list
    contacts_first: list  # activations of each contact before the top ball's first apex

    def top(self, n: int) -> list:
        """The heights of the top ball's apexes (``n`` balls)."""
        return [h for ball, _, h in self.apexes if ball == n - 1]


def inputs(mass_ratios, eps, tau_ratios, height: float) -> tuple:
    """(masses, lam, heights at release) of a Hertz stack, from the model's public functions:
    the values the solvers are handed."""
    from twoball.stacks import check_stack, hertz

    stack = check_stack(mass_ratios, eps, tau_ratios, height=height, force="hertz")
    restitutions = np.asarray(stack.eps, dtype=float)
    lam = np.array([hertz.damping_factor(float(e)) for e in restitutions])
    lam /= hertz.calibration_speeds(stack.masses, restitutions, height)
    return stack.masses.copy(), lam, stack.x_start.copy()  # (released in the Hertz units)


def _product(a: list, b: list, k: int):
    """Coefficient k of the product of two series."""
    return mpmath.fsum(a[i] * b[k - i] for i in range(k + 1))


def _chain(factors: list, chains: list, k: int):
    """Coefficient k of the product of the series ``factors`` (``chains`` holds the partial
    products' coefficients so far; a list of lists, one per partial product)."""
    if not factors:
        return mpmath.mpf(1 if k == 0 else 0)
    chains[0].append(factors[0][k])
    for i in range(1, len(factors)):
        chains[i].append(_product(chains[i - 1], factors[i], k))
    return chains[len(factors) - 1][k]


def _series(masses, lam, x, v, rho, active) -> dict:
    """Taylor coefficients in tau, to ORDER, of t (from 0), x, v and the active contacts' rho."""
    n = len(masses)
    on = [c for c in range(n) if active[c]]
    zero, one = mpmath.mpf(0), mpmath.mpf(1)
    t_s = [zero]
    x_s = [[x[j]] for j in range(n)]
    v_s = [[v[j]] for j in range(n)]
    r_s = {c: [rho[c]] for c in on}
    square = {c: [] for c in on}
    cube = {c: [] for c in on}
    clamp = {c: [] for c in on}
    force = {c: [] for c in on}
    half = {c: [] for c in on}
    j_s, j_chains = [], [[] for _ in on]
    others = {c: [] for c in on}
    other_chains = {c: [[] for _ in on] for c in on}
    accel = [[] for _ in range(n)]
    for k in range(ORDER):
        for c in on:
            rate = v_s[c][k] - (v_s[c - 1][k] if c >= 1 else zero)
            square[c].append(_product(r_s[c], r_s[c], k))
            cube[c].append(_product(square[c], r_s[c], k))
            clamp[c].append((one if k == 0 else zero) - lam[c] * rate)
            force[c].append(_product(cube[c], clamp[c], k))
            half[c].append(-rate / 2)
        j_s.append(_chain([r_s[c] for c in on], j_chains, k))
        for c in on:
            others[c].append(_chain([r_s[d] for d in on if d != c], other_chains[c], k))
        for j in range(n):
            below = force[j][k] if j in force else zero
            above = force[j + 1][k] if j + 1 in force else zero
            accel[j].append((-one if k == 0 else zero) + (below - above) / masses[j])
        t_s.append(j_s[k] / (k + 1))
        for j in range(n):
            x_s[j].append(_product(j_s, v_s[j], k) / (k + 1))
            v_s[j].append(_product(j_s, accel[j], k) / (k + 1))
        for c in on:
            r_s[c].append(_product(others[c], half[c], k) / (k + 1))
    return {"t": t_s, "x": x_s, "v": v_s, "rho": r_s}


def _step(series: dict):
    """The step in tau at which the last two terms of every series are below TOLERANCE,
    relative to the variable (at least 1)."""
    step = mpmath.mpf(MAX_STEP)
    every = [series["t"], *series["x"], *series["v"], *series["rho"].values()]
    for coefficients in every:
        scale = max(abs(coefficients[0]), mpmath.mpf(1))
        for k in (ORDER - 1, ORDER):
            if coefficients[k] != 0:
                step = min(step, (TOLERANCE * scale / abs(coefficients[k])) ** (mpmath.mpf(1) / k))
    return step


def _horner(coefficients: list, tau):
    total = mpmath.mpf(0)
    for c in reversed(coefficients):
        total = total * tau + c
    return total


def _state(series: dict, tau) -> tuple:
    """(t since the step's start, x, v, rho) at tau."""
    return (
        _horner(series["t"], tau),
        [_horner(c, tau) for c in series["x"]],
        [_horner(c, tau) for c in series["v"]],
        {c: _horner(r, tau) for c, r in series["rho"].items()},
    )


def _functions(lam, x, v, rho, active) -> list:
    """Every watched quantity, as (kind, index, value): each falls through zero at its event.
    A contact is active while max(eta, lam eta' - 1) < 0 (docs/model.md, "Bodies, coordinates,
    forces"); an active contact ends when rho = sqrt(delta) or 1 + lam delta' falls through zero;
    a ball in no active contact has an apex when its velocity does."""
    n = len(x)
    out = []
    for c in range(n):
        eta = x[c] - (x[c - 1] if c >= 1 else 0)
        clamp = 1 - lam[c] * (v[c] - (v[c - 1] if c >= 1 else 0))
        if active[c]:
            out.append(("release", c, rho[c]))
            out.append(("clamp", c, clamp))
        else:
            out.append(("touch", c, max(eta, -clamp)))
    for j in range(n):
        if not active[j] and not (j + 1 < n and active[j + 1]):
            out.append(("apex", j, v[j]))
    return out


def _falls(kind: str, before, after) -> bool:
    if kind == "apex":
        return before > 0 and after <= 0
    return before >= 0 and after < 0


def solve_hertz_truth(masses, lam, x_start, apexes_wanted: int = 2) -> HertzTruth:
    """Run a Hertz stack from rest at ``x_start`` to the top ball's ``apexes_wanted``-th apex."""
    with mpmath.workdps(DIGITS):
        n = len(masses)
        m = [mpmath.mpf(float(value)) for value in masses]
        damping = [mpmath.mpf(float(value)) for value in lam]
        x = [mpmath.mpf(float(value)) for value in x_start]
        v = [mpmath.mpf(0)] * n
        t = mpmath.mpf(0)
        active = [False] * n
        rho = {}
        apexes, first, top = [], [0] * n, 0
        for _ in range(MAX_STEPS):
            series = _series(m, damping, x, v, rho, active)
            h = _step(series)
            before = _functions(damping, x, v, rho, active)
            low, found = mpmath.mpf(0), None
            for probe in range(1, PROBES + 2):
                tau = h * probe / (PROBES + 1)
                _, xs, vs, rs = _state(series, tau)
                after = _functions(damping, xs, vs, rs, active)
                hits = [
                    i
                    for i, (b, a) in enumerate(zip(before, after, strict=True))
                    if _falls(b[0], b[2], a[2])
                ]
                if hits:
                    found = min((_refine(series, damping, active, i, low, tau), i) for i in hits)
                    break
                before, low = after, tau
            tau = found[0] if found else h
            elapsed, x, v, rho = _state(series, tau)
            t += elapsed
            if not found:
                continue
            kind, index, _ = before[found[1]]
            if kind == "apex":
                v[index] = mpmath.mpf(0)
                apexes.append((index, t, x[index]))
                if index == n - 1:
                    top += 1
                    if top == apexes_wanted:
                        break
            elif kind == "touch":
                active[index] = True
                eta = x[index] - (x[index - 1] if index >= 1 else 0)
                # a touch starts at delta = 0 (eta is then rounding); a clamped contact that
                # pushes again starts compressed
                rho[index] = mpmath.sqrt(-eta) if eta < -(mpmath.mpf(10) ** -15) else mpmath.mpf(0)
                if top == 0:
                    first[index] += 1
            else:
                active[index] = False
                del rho[index]
        else:
            raise RuntimeError("the Hertz reference ran out of steps")
        return HertzTruth(apexes, first)


def _refine(series, damping, active, which: int, low, high):
    """Bisection on the series for the tau in (low, high] at which function ``which`` falls."""
    kind = None
    while high - low > mpmath.mpf(10) ** (4 - DIGITS) * high:
        middle = (low + high) / 2
        _, xs, vs, rs = _state(series, middle)
        kind, _, value = _functions(damping, xs, vs, rs, active)[which]
        if _falls(kind, 1, value):
            high = middle
        else:
            low = middle
    return high


# --- the accuracy table (docs/accuracy.md, "The Hertz stack"): seeded drops ----------------------

SEED = 7
DROPS_PER_SIZE = 8  # for each of N = 2, 3, 4
TOLERANCE_H = 1e-10  # h1 and h2 within this of the reference, or ten times their conditioning


def cases(seed: int = SEED, per_size: int = DROPS_PER_SIZE) -> list[dict]:
    """Seeded drops: N = 2 to 4, each mass ratio log-uniform in [0.05, 1], one eps uniform in
    [0.5, 1] (every fourth drop elastic, eps = 1), one gap uniform in [0.05, 1], H log-uniform in
    [1e2, 1e5]."""
    rng = np.random.default_rng(seed)
    drops = []
    for balls in (2, 3, 4):
        for i in range(per_size):
            ratios = [float(10 ** rng.uniform(np.log10(0.05), 0.0)) for _ in range(balls - 1)]
            eps = 1.0 if i % 4 == 0 else float(rng.uniform(0.5, 1.0))
            drops.append(
                {
                    "mass_ratios": ratios,
                    "eps": eps,
                    "tau_ratios": float(rng.uniform(0.05, 1.0)),
                    "height": float(10 ** rng.uniform(2.0, 5.0)),
                }
            )
    return drops


def reference(case: dict) -> dict:
    """The reference's h1, h2 (text, 25 digits) and contacts before h1, for one drop."""
    masses, lam, x_start = inputs(
        case["mass_ratios"], case["eps"], case["tau_ratios"], case["height"]
    )
    truth = solve_hertz_truth(masses, lam, x_start)
    top = truth.top(len(masses))
    return {
        "h1_truth": mpmath.nstr(top[0], 25),
        "h2_truth": mpmath.nstr(top[1], 25),
        "contacts_first_truth": " ".join(str(k) for k in truth.contacts_first),
    }


def _heights(case: dict, **changed) -> np.ndarray:
    from twoball.stacks import simulate_stack

    args = {**case, **changed}
    result = simulate_stack(
        args["mass_ratios"], args["eps"], args["tau_ratios"], height=args["height"], force="hertz"
    )
    return np.array([result.h1, result.h2])


def conditioning(case: dict) -> np.ndarray:
    """(cond_h1, cond_h2) of a Hertz drop, measured as twoball.studies.conditioning measures a
    two-ball drop's: the relative move of h1 and h2 per one-ulp move of each input (each mass
    ratio, eps, the gap, H), by central differences over 2^16 ulps, summed."""
    return difference_conditioning(case, _heights)
