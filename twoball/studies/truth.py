"""A slow, high-precision reference for the exact solver: mpmath at 40 digits.

It shares no code with :mod:`twoball.exact` (only the validated inputs of
:func:`twoball.model.check_parameters`, converted exactly to mpmath numbers, so that both solve
the same equations with the same coefficients). The method is deliberately different:

- The state y = (x1, x2, v1, v2, 1) of a phase obeys y' = A y, with A the phase's 5x5 matrix
  (docs/model.md, "Bodies, coordinates, forces": the equations of motion with the active contacts'
  forces, gravity carried by the constant fifth component). A phase is walked in steps of dt with
  the propagator expm(A dt) from ``mpmath.expm``.
- Every switching quantity is a linear function of y: the overlap eta, g = eta + 2 zeta eta'
  and their rates (rows of A and A^2). A contact is active while max(eta, g) < 0 (docs/model.md,
  "Bodies, coordinates, forces"); the
  apex is v2 falling through zero while the ball contact is inactive ("What is measured").
- A switch is looked for at each step's end and, to catch a touch that dips in and out within a
  step, at the extremum of eta and of g inside the step (where their rate changes sign). It is
  then refined by bisection to ~1e-37 with the state inside the step from its Taylor series
  (|A dt| <= 1/8, 36 terms, exact to the working precision).

dt is 1/8 of 1/||A|| in a contact phase (the shortest time scale of the phase, e.g.
sqrt(mu/(1 + mu)) for the ball contact); 8 in free flight, where the series is finite. It
handles benign cases (a few contacts, no rest) in seconds per case. Call :func:`solve_truth`.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

import mpmath

from twoball.model import DEFAULT_HEIGHT, check_parameters

DIGITS = 40
TAYLOR_TERMS = 36
STEP_FRACTION = 8  # dt = 1 / (STEP_FRACTION * ||A||_inf) in a contact phase
FREE_FLIGHT_STEP = 8
MAX_PHASES = 400
MAX_STEPS = 2_000_000


@dataclass(frozen=True)
class Truth:
    """Apex heights and times and contact intervals (floor and ball), as mpmath numbers."""

    apex_t: list
    apex_h: list
    contacts: list  # (contact, start, end): 0 floor, 1 ball
    contacts_first: list[int]  # intervals of each contact before the first apex, as a Result's

    @property
    def h1(self):
        return self.apex_h[0] if self.apex_h else None

    @property
    def h2(self):
        return self.apex_h[1] if len(self.apex_h) > 1 else None


def _phase_matrix(floor_on: bool, ball_on: bool, mu, z01, z12) -> mpmath.matrix:
    """y' = A y for y = (x1, x2, v1, v2, 1) with the given contacts active (docs/model.md, "Bodies,
    coordinates, forces")."""
    a = mpmath.matrix(5, 5)
    a[0, 2] = a[1, 3] = 1
    a[2, 4] = a[3, 4] = -1  # gravity
    if floor_on:  # f01 = -(x1 + 2 z01 v1) on the lower ball
        a[2, 0] -= 1
        a[2, 2] -= 2 * z01
    if ball_on:  # f12 = -(x2 - x1) - 2 z12 (v2 - v1): -f12 on the lower, +f12/mu on the upper
        row = [1, -1, 2 * z12, -2 * z12]
        for j in range(4):
            a[2, j] -= row[j]
            a[3, j] += row[j] / mu
    return a


def _row_times(row: list, a: mpmath.matrix) -> list:
    return [mpmath.fsum(row[i] * a[i, j] for i in range(5)) for j in range(5)]


def _dot(row: list, y: mpmath.matrix):
    return mpmath.fsum(row[i] * y[i] for i in range(5))


class _Phase:
    """One phase: its matrix, step propagator and the rows of every switching quantity."""

    def __init__(self, kind: int, mu, z01, z12):
        self.kind = kind
        self.a = _phase_matrix(bool(kind & 1), bool(kind & 2), mu, z01, z12)
        norm = max(mpmath.fsum(abs(self.a[i, j]) for j in range(5)) for i in range(5))
        # free flight: A is nilpotent (A^3 = 0), the series ends after three terms and every
        # switching quantity is at most quadratic, so one extremum check per step suffices
        self.dt = mpmath.mpf(FREE_FLIGHT_STEP) if kind == 0 else 1 / (STEP_FRACTION * norm)
        self.step = mpmath.expm(self.a * self.dt)
        self.rows = {}
        for contact, zeta in ((0, z01), (1, z12)):
            eta = [1, 0, 0, 0, 0] if contact == 0 else [-1, 1, 0, 0, 0]
            eta = [mpmath.mpf(v) for v in eta]
            deta = _row_times(eta, self.a)
            ddeta = _row_times(deta, self.a)
            g = [eta[i] + 2 * zeta * deta[i] for i in range(5)]
            dg = [deta[i] + 2 * zeta * ddeta[i] for i in range(5)]
            self.rows[contact] = (eta, deta, g, dg)

    def series(self, y: mpmath.matrix) -> list:
        """Coefficients c_k = A^k y / k! of y(h) = sum c_k h^k (|A dt| <= 1/8, or A nilpotent
        in free flight, where the series ends)."""
        coefficients = [list(y)]
        term = y
        for k in range(1, TAYLOR_TERMS):
            term = (self.a * term) / k
            if not any(term):
                break
            coefficients.append(list(term))
        return coefficients

    @staticmethod
    def state(coefficients: list, h) -> list:
        """y(h) from :meth:`series` by Horner's rule, for 0 <= h <= dt."""
        total = list(coefficients[-1])
        for c in reversed(coefficients[:-1]):
            total = [total[i] * h + c[i] for i in range(5)]
        return total

    def active(self, contact: int, y: mpmath.matrix) -> bool:
        eta, _, g, _ = self.rows[contact]
        return max(_dot(eta, y), _dot(g, y)) < 0

    def wrong_side(self, event: int, y: mpmath.matrix) -> bool:
        """True once the event has happened: a contact changed state, or the apex passed."""
        if event == 2:
            return y[3] <= 0
        return self.active(event, y) != bool(self.kind & (1 << event))

    def first_time(self, event: int, y: mpmath.matrix, y_next: mpmath.matrix):
        """Time in (0, dt] of the first occurrence of ``event`` after y, or None."""
        extrema = []
        if event < 2:
            _, deta, _, dg = self.rows[event]
            for rate in (deta, dg):
                r0, r1 = _dot(rate, y), _dot(rate, y_next)
                if (r0 < 0 < r1) or (r0 > 0 > r1):  # an extremum inside the step
                    extrema.append((rate, r0))
        if not extrema and not self.wrong_side(event, y_next):
            return None
        coefficients = self.series(y)
        candidates = [
            self._bisect(lambda z, rate=rate, r0=r0: (_dot(rate, z) > 0) == (r0 < 0), coefficients)
            for rate, r0 in extrema
        ]
        for t_candidate in [*sorted(candidates), self.dt]:
            at = self.state(coefficients, t_candidate) if t_candidate < self.dt else y_next
            if self.wrong_side(event, at):
                return self._bisect(lambda z: self.wrong_side(event, z), coefficients, t_candidate)
        return None

    def _bisect(self, happened, coefficients: list, high=None):
        """Smallest h in (0, high] with happened(y(h)) (a single change assumed)."""
        high = self.dt if high is None else high
        low = mpmath.mpf(0)
        tiny = mpmath.mpf(10) ** (3 - mpmath.mp.dps)
        while high - low > tiny:
            mid = (low + high) / 2
            if happened(self.state(coefficients, mid)):
                high = mid
            else:
                low = mid
        return high


def solve_truth(
    eps: float,
    mu: float,
    tau_ratio: float,
    *,
    eps12: float | None = None,
    height: float = DEFAULT_HEIGHT,
    apexes: int = 2,
    nudge: tuple[int, int] | None = None,
    round_heights: int | None = None,
) -> Truth:
    """Apexes and contacts of one drop at 40 digits, independently of the exact solver.

    For benign cases only (see the module docstring); raises RuntimeError if the wanted apexes
    are not reached within MAX_PHASES phases or MAX_STEPS steps (e.g. the ball came to rest).
    ``nudge=(component, ulps)`` moves one component of the state (x1, x2, v1, v2) by that many
    double ulps at the first apex, to measure how sensitive the rest of the run is to the
    rounding of the state there (docs/accuracy.md, "Many-contact drops").
    ``round_heights=seed`` moves the heights x1, x2 by half a double ulp, up or down at random
    (seeded), at every switch before the first apex: the least rounding a solver that hands
    absolute heights from phase to phase makes there.
    """
    drop = check_parameters(eps, mu, tau_ratio, eps12=eps12, height=height)
    coin = random.Random(round_heights)
    with mpmath.workdps(DIGITS):
        mu_, z01, z12 = (mpmath.mpf(v) for v in (drop.mu, drop.zeta01, drop.zeta12))
        phases = {}
        y = mpmath.matrix([mpmath.mpf(drop.x1_0), mpmath.mpf(drop.x2_0), 0, 0, 1])
        t = mpmath.mpf(0)
        kind = 0
        started = [None, None]
        apex_t, apex_h, contacts = [], [], []
        contacts_first = [0, 0]
        steps = 0
        for _ in range(MAX_PHASES):
            if kind not in phases:
                phases[kind] = _Phase(kind, mu_, z01, z12)
            phase = phases[kind]
            while True:
                # an apex only where the ball contact does not push; v2 then falls as t, so
                # once v2 <= 0 there is none left in this phase
                watched = (0, 1) if kind & 2 or y[3] <= 0 else (0, 1, 2)
                steps += 1
                if steps > MAX_STEPS:
                    raise RuntimeError("truth: step limit reached")
                y_next = phase.step * y
                times = {}
                for event in watched:
                    found = phase.first_time(event, y, y_next)
                    if found is not None:
                        times[event] = found
                if times:
                    event = min(times, key=times.get)
                    h = times[event]
                    y = mpmath.matrix(phase.state(phase.series(y), h))
                    t += h
                    break
                y = y_next
                t += phase.dt
            if event == 2:
                apex_t.append(t)
                apex_h.append(y[1])
                if nudge is not None and len(apex_t) == 1:
                    component, ulps = nudge
                    y[component] += ulps * math.ulp(float(y[component]))
                if len(apex_t) == apexes:
                    return Truth(apex_t, apex_h, contacts, contacts_first)
                continue
            if round_heights is not None and not apex_t:
                for component in (0, 1):
                    half_ulp = 0.5 * math.ulp(float(y[component]))
                    y[component] += coin.choice((-half_ulp, half_ulp))
            bit = 1 << event
            if kind & bit:
                contacts.append((event, started[event], t))
            else:
                started[event] = t
                if not apex_t:
                    contacts_first[event] += 1
            kind ^= bit
        raise RuntimeError("truth: phase limit reached")
