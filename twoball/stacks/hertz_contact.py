"""One Hertz contact with Hunt-Crossley damping, calibrated to a restitution (docs/model.md,
"Stacks of N balls"; :mod:`twoball.stacks.hertz` has the model): the damping factor Lambda(eps),
each contact's calibration speed, and the floor contact time that sets a Hertz stack's gaps."""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


@functools.lru_cache(maxsize=256)
def _normalised_contact(factor: float) -> tuple[float, float]:
    """(restitution, duration) of u'' = -u^(3/2) (1 + factor u'), u(0) = 0, u'(0) = 1, the
    contact ending when u returns to 0 or the force reaches zero (the clamp)."""

    def rhs(_t, y):
        u, du = y
        return [du, -(max(u, 0.0) ** 1.5) * (1.0 + factor * du)]

    def back_to_zero(_t, y):
        return y[0]

    def clamp(_t, y):
        return 1.0 + factor * y[1]

    back_to_zero.terminal, back_to_zero.direction = True, -1.0
    clamp.terminal, clamp.direction = True, -1.0
    solution = solve_ivp(
        rhs, (0.0, 100.0), [1e-300, 1.0], method="DOP853", rtol=1e-13, atol=1e-15,
        events=[back_to_zero, clamp], dense_output=False,
    )  # fmt: skip
    ends = [(e[0], k) for k, e in enumerate(solution.t_events) if len(e)]
    end, which = min(ends)
    speed = solution.y_events[which][0][1]
    return -speed, end


@functools.lru_cache(maxsize=256)
def damping_factor(eps: float) -> float:
    """Lambda = lam v with an isolated Hunt-Crossley contact's restitution equal to eps."""
    if eps >= 1.0 or _normalised_contact(0.0)[0] <= eps:
        # within the integration's error of elastic (eps = 1 - 1e-16 has no root in (0, high))
        return 0.0
    high = 1.0
    while _normalised_contact(high)[0] > eps:
        high *= 2.0
    return brentq(lambda f: _normalised_contact(f)[0] - eps, 0.0, high, xtol=1e-14, rtol=1e-13)


def calibration_speeds(masses: np.ndarray, eps: np.ndarray, height: float) -> np.ndarray:
    """Each contact's closing speed in the ICM chain (the floor's: sqrt(2H))."""
    impact = math.sqrt(2.0 * height)
    speeds = np.empty(len(masses))
    speeds[0] = impact
    up = eps[0] * impact
    for i in range(1, len(masses)):
        speeds[i] = up + impact
        below, mass = masses[i - 1], masses[i]
        up = (below * up - mass * impact + eps[i] * below * (up + impact)) / (below + mass)
    return speeds


def floor_contact_time(eps0: float, height: float) -> float:
    """tau_f of the calibrated floor contact of ball 0 (mass 1) at impact speed sqrt(2H)."""
    speed = math.sqrt(2.0 * height)
    return speed ** (-0.2) * _normalised_contact(damping_factor(eps0))[1]
