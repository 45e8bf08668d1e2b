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


# Lambda at the app's eps slider steps, k / 100 for k = 30 to 100 (app/state.py, stack_eps), as
# _calibrated computes them (tests/test_hertz.py computes each again): a Stack scene's move to an
# eps not met before then pays no calibration, 35 ms of scipy (80-190 ms on a loaded server;
# docs/performance.md, "The Stack scene's forces")
SLIDER_STEPS = range(30, 101)
# fmt: off
SLIDER_FACTORS = (
    3.0870819811292356, 2.9619079517784592, 2.8434917656183423,
    2.731259735043479, 2.6247049766957478, 2.5233777059466767,
    2.4268771918462186, 2.3348450498081452, 2.246959618997073,
    2.1629312243137915, 2.0824981641470948, 2.0054232967169257,
    1.931491122731988, 1.8605052815728167, 1.7922863937109124,
    1.7266701942466223, 1.6635059123384683, 1.6026548592319736,
    1.5439891937759198, 1.4873908397335542, 1.4327505332711834,
    1.3799669824556577, 1.32894612352632, 1.2796004610245229,
    1.2318484807282073, 1.1856141261277784, 1.1408263304004986,
    1.097418597027788, 1.0553286231828485, 1.0144979607811235,
    0.9748717108128795, 0.9363982471254263, 0.8990289663480122,
    0.8627180610632401, 0.8274223136850778, 0.7931009088576054,
    0.7597152623823386, 0.7272288650056259, 0.6956071395322603,
    0.6648173099329622, 0.6348282812660095, 0.6056105293634644,
    0.5771359993488708, 0.5493780121541033, 0.5223111782934688,
    0.49591131823399404, 0.4701553887668104, 0.44502141484741187,
    0.420488426424897, 0.39653639983613054, 0.37314620336218796,
    0.3502995466289629, 0.32797893347216417, 0.30616761807251974,
    0.28484956401416583, 0.26400940608312856, 0.24363241456807447,
    0.22370446189581542, 0.2042119913687702, 0.1851419879230744,
    0.16648195068494095, 0.14821986723384953, 0.13034418943446,
    0.11284381071963598, 0.0957080447475176, 0.07892660528720749,
    0.06248958729974916, 0.04638744910027857, 0.03061099553439241,
    0.015151362108965873, 0.0,
)
# fmt: on


@functools.lru_cache(maxsize=256)
def damping_factor(eps: float) -> float:
    """Lambda = lam v with an isolated Hunt-Crossley contact's restitution equal to eps: at k /
    100 the slider's (:data:`SLIDER_FACTORS`), else calibrated (:func:`_calibrated`)."""
    k = round(eps * 100.0) if math.isfinite(eps) else -1
    if k in SLIDER_STEPS and eps == k / 100:
        return SLIDER_FACTORS[k - SLIDER_STEPS.start]
    return _calibrated(eps)


def _calibrated(eps: float) -> float:
    """Lambda with the restitution of :func:`_normalised_contact` equal to eps (brentq)."""
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
