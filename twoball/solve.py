"""The public entry point: one drop, one method, what the caller asked for and nothing more."""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

from numpy.typing import ArrayLike

from twoball import cvode, exact, reference
from twoball.errors import ParameterError, SolverError, Status, phase_limit_hint
from twoball.model import (
    DEFAULT_HEIGHT,
    apex_bound,
    beyond_bound,
    check_flag,
    check_parameters,
    with_ranges,
)
from twoball.observables import (
    Outcome,
    Result,
    as_times,
    check_span,
    contact_intervals,
    stop_rule,
    trajectory_of,
)

# Every method by name, as scipy's ``integrate._ivp.ivp.METHODS``: one signature,
# solve(drop, apexes, t_end, *, rtol, atol, dense_output) -> Outcome. rtol and atol are None for
# "exact" (it has none) and reference.DEFAULT_TOL unless given for the others. CVODE needs the
# cvode extra (imported when it runs).
Solver = Callable[..., Outcome]
METHODS: dict[str, Solver] = {
    "exact": exact.solve,
    **{name: partial(reference.solve, method=name) for name in reference.METHODS},
    "CVODE": cvode.solve,
}
_METHOD_NAMES = {name.lower(): name for name in METHODS}


@with_ranges
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
    t_eval: ArrayLike | None = None,
    dense_output: bool = False,
    throw: bool = True,
) -> Result:
    """Drop the two balls and measure their bounces (docs/model.md, "What is measured").

    Parameters
    ----------
    eps, eps12 : float
        Restitution of the floor and of the ball contact, in RANGE(eps); ``eps12`` defaults to
        ``eps``.
    mu : float
        Mass ratio m2/m1 in RANGE(mu).
    tau_ratio : float
        tau_d/tau_f in RANGE(tau_ratio) (docs/model.md, "Initial condition").
    height : float
        Dimensionless drop height H in RANGE(height); with the gap, within the domain double
        precision can carry (docs/model.md, "The domain double precision can carry").
    until : "first", "second" or float
        The apex of the upper ball to run to, or a dimensionless time. A run also ends early
        when the upper ball comes to rest on the lower one (``Result.status`` is ``REST``).
    method : str
        "exact" (closed form, the default), or a reference: "LSODA", "Radau", "BDF",
        "DOP853", "RK45" (solve_ivp with events), "odeint" (the paper's fixed grid), "CVODE"
        (SUNDIALS BDF with root finding; the ``cvode`` extra, no dense output).
    rtol, atol : float, optional
        Tolerances of the reference methods only (default 1e-8).
    t_eval : array_like, optional
        Times at which ``Result.trajectory`` samples the state and the forces.
    dense_output : bool
        Keep a solution that ``Result.evaluate(t)`` evaluates at any times (exactly, for the
        exact method); without ``t_eval`` the trajectory is then sampled at plotting times
        that show every contact (``Result.plot_times``), when it is first read.
    throw : bool
        A run that fails (the root finder stuck, the phase limit, a scipy method's failure or
        no apex before its horizon, an apex that is not finite or above what the energy at
        release allows) raises :class:`~twoball.errors.SolverError` (the default); with
        ``throw=False`` (batch callers, as diffrax's ``throw``) it returns a Result whose
        ``success`` is False and whose ``status`` and ``reason`` say what happened.

    Returns
    -------
    Result
        Apexes, contacts (numbered: 0 the floor, 1 the balls), ``contacts_first`` (the
        intervals of each before the first apex, ``[floor, balls]``), ratios, ``status`` and
        ``success``.

    Raises
    ------
    ParameterError
        A ``ValueError`` naming the parameter and its allowed range, also for a drop outside
        the domain double precision can carry (docs/model.md, "The domain double precision can
        carry").

    Examples
    --------
    The paper's close-up case: four ball contacts in the first bounce, then a delayed rebound.

    >>> import twoball
    >>> r = twoball.simulate(0.9, 0.01, 0.01)
    >>> r.contacts_first, round(r.h1, 5), round(r.h2, 4), r.delayed_rebound
    ([1, 4], 9256.04845, 50076.3922, True)
    >>> r.success, r.status.name
    (True, 'DONE')
    """
    drop = check_parameters(eps, mu, tau_ratio, eps12=eps12, height=height)
    dense_output, throw = check_flag("dense_output", dense_output), check_flag("throw", throw)
    apexes, t_end = stop_rule(until)
    # in any case ("cvode", as its extra is called, or "dop853"): named as METHODS names it
    method = _METHOD_NAMES.get(method.lower(), method) if isinstance(method, str) else method
    if method not in METHODS:
        raise ParameterError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if tol is not None and not (math.isfinite(tol) and 0.0 < tol < 1.0):
            raise ParameterError(f"{name} must be a finite number in (0, 1); got {tol!r}")
    times = None
    if t_eval is not None:
        times = as_times("t_eval", t_eval)
        check_span("t_eval", times, math.inf, False)  # no time before the release
    keep = dense_output or times is not None
    if method != "exact":  # a reference method: its tolerances, defaulted once here
        rtol = reference.DEFAULT_TOL if rtol is None else rtol
        atol = reference.DEFAULT_TOL if atol is None else atol
    outcome = METHODS[method](drop, apexes, t_end, rtol=rtol, atol=atol, dense_output=keep)
    if outcome.status is Status.PHASE_LIMIT and outcome.message:
        outcome = outcome._replace(message=outcome.message + phase_limit_hint(drop.eps))
    failure = _failure(outcome.message, outcome.apex_h, drop)
    if failure:
        outcome = outcome._replace(status=Status.IMPOSSIBLE, message=failure)
    trajectory = plot_times = None
    if times is not None:
        at_rest = outcome.status is Status.REST and method == "exact"
        check_span("t_eval", times, float(outcome.end_time), at_rest)
        trajectory = trajectory_of(times, outcome.evaluate(times))
    elif dense_output:  # sampled when first read (Result.trajectory)
        plot_times = outcome.plot_times
    result = Result(
        drop=drop,
        method=method,
        apex_t=[float(t) for t in outcome.apex_t],
        apex_h=[float(h) for h in outcome.apex_h],
        contacts=contact_intervals(outcome.contacts),
        end_time=float(outcome.end_time),
        reason=outcome.message,
        contacts_first=outcome.contacts_first,  # Python ints from every solver
        rtol=rtol,
        atol=atol,
        trajectory=trajectory,
        status=outcome.status,
        dense=outcome.evaluate if dense_output else None,
        stats=outcome.stats,
        plot_times=plot_times,
    )
    if throw and not result.success:
        raise SolverError(f"{method} failed on {drop}: {result.reason}", result)
    return result


def _failure(reason: str | None, apex_h: list[float], drop) -> str | None:
    """Why the apexes cannot be right (not finite, or above the energy bound), else None."""
    bound = apex_bound(drop)
    for number, height in enumerate(apex_h, start=1):
        if beyond_bound(height, bound):
            return (
                f"apex {number} at {height:.6g} is impossible: the energy at release allows "
                f"{bound:.6g} at most ({reason or 'no reason given by the solver'})"
            )
    return None
