"""The public entry point: one drop, one method, what the caller asked for and nothing more."""

from __future__ import annotations

import math

import numpy as np

from twoball import exact, reference
from twoball.errors import ParameterError
from twoball.model import DEFAULT_HEIGHT, check_parameters
from twoball.observables import Result, Trajectory, contact_intervals

METHODS = ("exact", *reference.METHODS)
UNTIL = {"first": 1, "second": 2}
# A run "until a time" records apexes up to this many (a bound on the kernel's apex table).
MAX_APEXES = 100_000


def simulate(
    eps: float,
    mu: float,
    tau_ratio: float,
    *,
    eps12: float | None = None,
    height: float = DEFAULT_HEIGHT,
    until: str | float = "second",
    method: str = "exact",
    rtol: float | None = None,
    atol: float | None = None,
    dense: bool | np.ndarray = False,
) -> Result:
    """Drop the two balls and measure their bounces (docs/model.md, "What is measured").

    eps, eps12: restitution of the floor and the ball contact (eps12 defaults to eps), in (0, 1].
    mu: mass ratio m2/m1 > 0. tau_ratio: tau_d/tau_f >= 0. height: dimensionless H > 0.
    until: "first" or "second" apex of the upper ball, or a dimensionless time; a run also ends
    early when the upper ball comes to rest on the lower one (``Result.reason`` says so).
    method: "exact" (closed form, the default), or a scipy reference: "LSODA", "Radau", "BDF",
    "DOP853", "RK45" (solve_ivp with events), "odeint" (the paper's fixed grid); rtol and atol
    apply to these only (default 1e-8).
    dense: False (no trajectory is computed), True (a plotting grid), or an array of times.

    Raises ValueError naming the parameter and its allowed range.
    """
    drop = check_parameters(eps, mu, tau_ratio, eps12=eps12, height=height)
    apexes, t_end = _stop_rule(until)
    if method not in METHODS:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if tol is not None and not (math.isfinite(tol) and 0.0 < tol < 1.0):
            raise ParameterError(f"{name} must be a finite number in (0, 1); got {tol!r}")
    if method == "exact":
        if rtol is not None or atol is not None:
            raise ParameterError("rtol and atol apply to the scipy methods only, not to 'exact'")
        outcome = exact.solve(drop, apexes, t_end, dense=dense)
    else:
        outcome = reference.solve(drop, method, apexes, t_end, rtol, atol, dense)
    apex_t, apex_h, rows, end, reason, ball_first, floor_first, samples = outcome
    trajectory = None
    if samples is not None:
        times, values = samples
        trajectory = Trajectory(times, *(np.ascontiguousarray(values[:, i]) for i in range(6)))
    return Result(
        drop=drop,
        method=method,
        apex_t=[float(t) for t in apex_t],
        apex_h=[float(h) for h in apex_h],
        contacts=contact_intervals(rows),
        end_time=float(end),
        reason=reason,
        contacts_first=int(ball_first),
        floor_contacts_first=int(floor_first),
        rtol=None if method == "exact" else (rtol or reference.DEFAULT_TOL),
        atol=None if method == "exact" else (atol or reference.DEFAULT_TOL),
        trajectory=trajectory,
    )


def _stop_rule(until: str | float) -> tuple[int, float]:
    """(apexes wanted, end time) for an ``until`` argument."""
    if isinstance(until, str):
        if until not in UNTIL:
            raise ParameterError(f"until must be 'first', 'second' or a time > 0; got {until!r}")
        return UNTIL[until], math.inf
    try:
        t_end = float(until)
    except (TypeError, ValueError):
        raise ParameterError(
            f"until must be 'first', 'second' or a time > 0; got {until!r}"
        ) from None
    if not (math.isfinite(t_end) and t_end > 0.0):
        raise ParameterError(f"until must be 'first', 'second' or a finite time > 0; got {until!r}")
    return MAX_APEXES, t_end
