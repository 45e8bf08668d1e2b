"""``simulate_stack``: a stack of N balls dropped and measured (docs/model.md, "Stacks of N
balls"). The linear force runs the compiled N-ball kernel (:mod:`twoball.kernels.stack`; the
method, and why no contact can be missed, in :mod:`twoball.kernels.clusters`), the Hertz force
:mod:`twoball.stacks.hertz`."""

from __future__ import annotations

import gc
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial

import numpy as np

from twoball.errors import ParameterError, SolverError, Status, phase_limit_hint

# by module, not by name: jit.use_python_kernels swaps the kernels in their own modules
from twoball.kernels import clusters
from twoball.kernels import stack as kernel
from twoball.model import DEFAULT_HEIGHT, beyond_bound, check_flag
from twoball.observables import ContactInterval, RunStats, as_times, check_span, stop_rule
from twoball.stacks.model import (
    Stack,
    StackResult,
    StackTrajectory,
    _apex_bound,
    check_stack,
)


def solver_for(force: str, method: str) -> StackSolver:
    """The solver of ``method`` for ``force`` (:data:`METHODS`); ``ParameterError`` naming the
    methods that force has, where it has no such method."""
    solvers = METHODS[force]
    if method not in solvers:
        elsewhere = [other for other, named in METHODS.items() if method in named]
        hint = f" (it applies to the {elsewhere[0]} force only)" if elsewhere else ""
        if method == "exact":  # the two-ball name of the exact solver
            hint = " ('compiled' is the stacks' exact solver)"
        raise ParameterError(
            f"method must be one of {', '.join(solvers)} with the {force} force; got {method!r}"
            + hint
        )
    return solvers[method]


def simulate_stack(
    mass_ratios: object,
    eps: object,
    tau_ratios: object,
    *,
    height: float = DEFAULT_HEIGHT,
    force: str = "linear",
    until: str | float = "second",
    t_eval: object = None,
    nan_past_end: bool = False,
    dense_output: bool = False,
    throw: bool = True,
    method: str = "compiled",
) -> StackResult:
    """Drop a stack of N balls and measure the top ball's bounces (docs/model.md, "Stacks of N
    balls").

    Parameters
    ----------
    mass_ratios : sequence of float
        The N - 1 ratios m_i / m_(i-1), bottom up (for N = 2, ``[mu]``).
    eps : float or sequence of float
        One number for every contact, or a sequence of exactly N: the floor's, then each pair's
        (a sequence of another length, one value included, is refused).
    tau_ratios : float or sequence of float
        One number for every pair, or a sequence of exactly N - 1: ball i + 1 reaches its
        touching height td_i = tau_ratio_i * tau_f after ball i would, in free fall.
    height : float
        Dimensionless drop height H of ball 0.
    force : "linear" or "hertz"
        The contact force: the linear spring-dashpot, solved exactly, or Hertz's with
        Hunt-Crossley damping (:mod:`twoball.stacks.hertz`).
    until : "first", "second" or float
        The top ball's apex to run to, or a dimensionless time.
    t_eval : array_like, optional
        Times at which ``StackResult.trajectory`` samples heights, velocities and forces.
    nan_past_end : bool
        Times of ``t_eval`` past the run's end (when it did not end at rest) give NaN instead of
        a ParameterError: a run to an apex, whose time is not known beforehand, sampled in the
        same pass.
    dense_output : bool
        Keep what :meth:`StackResult.evaluate` needs to give the state at any times of the run
        once it has ended (its end is known then): the linear run's phases, the Hertz run's
        state at every step's end. Only when asked (a six-ball Hertz run keeps ~7 500 states);
        the compiled methods only.
    throw : bool
        A run that fails raises :class:`~twoball.errors.SolverError`; with False the result says
        so (``success``, ``status``).
    method : str
        A name of :data:`METHODS` for the force. With the Hertz force: "compiled", the compiled
        integrator, or "DOP853", scipy's, kept as a reference (:mod:`twoball.stacks.hertz`). The
        linear force has only "compiled" (its exact solver): any other is refused with
        ParameterError.

    Returns
    -------
    StackResult

    Examples
    --------
    With two balls it is :func:`twoball.simulate`:

    >>> import twoball
    >>> from twoball.stacks import simulate_stack
    >>> pair = simulate_stack([0.01], 0.9, 0.01)
    >>> single = twoball.simulate(0.9, 0.01, 0.01)
    >>> bool(abs(pair.h2 - single.h2) < 1e-9 * single.h2), pair.contacts_first[1]
    (True, 4)
    """
    stack = check_stack(mass_ratios, eps, tau_ratios, height=height, force=force)
    nan_past_end = check_flag("nan_past_end", nan_past_end)
    dense_output, throw = check_flag("dense_output", dense_output), check_flag("throw", throw)
    solve = solver_for(force, method)
    apexes_wanted, t_end = stop_rule(until)
    times = None
    if t_eval is not None:
        times = as_times("t_eval", t_eval)
        check_span("t_eval", times, math.inf, False)  # no time before the release
    result = solve(stack, apexes_wanted, t_end, times, dense_output)
    stack = result.stack  # (the stack the run reports: its apexes are bounded by it)
    # after the end the closed form (linear) would be extrapolated, or nothing sampled (Hertz);
    # after a proven rest every later state is that rest's
    if times is not None and nan_past_end and result.status is not Status.REST:
        _blank_past(result.trajectory, result.end_time)
    elif times is not None and result.status.success:
        check_span("t_eval", times, result.end_time, result.status is Status.REST)
    bound = _apex_bound(stack, force)
    if any(beyond_bound(h, bound) for h in result.apex_h):
        result.status = Status.IMPOSSIBLE
    result.reason = result.status.message or None
    if result.status is Status.PHASE_LIMIT:
        result.reason += phase_limit_hint(stack.eps[0])
    if throw and not result.success:
        raise SolverError(f"the stack run failed on {stack}: {result.reason}", result)
    return result


def _blank_past(trajectory: StackTrajectory, end_time: float) -> None:
    """NaN in every sample after ``end_time`` (with check_span's few ulp of slack)."""
    past = trajectory.t > end_time + 1e-12 * max(abs(end_time), 1.0)
    for rows in (trajectory.x, trajectory.v, trajectory.f):
        rows[past] = np.nan


def solve_linear(
    stack: Stack, apexes_wanted: int, t_end: float, times: np.ndarray | None, dense: bool
) -> StackResult:
    """The linear force's exact solver, the compiled N-ball kernel
    (:func:`twoball.kernels.stack.run`), on a validated stack: to ``apexes_wanted`` apexes of the
    top ball or ``t_end``, sampled at ``times`` if given; with ``dense`` its phases kept for
    :meth:`StackResult.evaluate`."""
    out = kernel.run(
        stack.masses,
        stack.zeta,
        stack.x_start,
        apexes_wanted,
        t_end,
        times is not None or dense,
        _store_for(stack),
    )
    with _collector_paused():
        # tolist: Python floats at once, not a numpy scalar per value (a third of the
        # three-ball drop's time outside the kernel)
        apexes = _apexes_by_ball(out.apexes, stack.balls)
        contacts = _intervals(out.contacts)
    states = partial(_linear_states, out.phases, stack)
    return StackResult(
        stack=stack,
        force="linear",
        method="compiled",
        apexes=apexes,
        contacts=contacts,
        contacts_first=[int(count) for count in out.contacts_first],
        end_time=float(out.end_time),
        status=Status(out.status),
        trajectory=None if times is None else states(times),
        stats=RunStats(phases=out.phase_count),
        dense=states if dense else None,
    )


def _apexes_by_ball(rows: np.ndarray, balls: int) -> list[list[tuple[float, float]]]:
    """Each ball's (time, height) apexes from the kernel's table (ball, time, height), in its
    order: row by row for a short table, by one mask a ball for a long one (about 6 000 rows
    to the eight-ball drop's second apex: 1.7 ms against 4.7 row by row; for three balls' 12
    rows the masks cost 27 us against 2)."""
    if rows.shape[0] < 64:
        apexes: list[list[tuple[float, float]]] = [[] for _ in range(balls)]
        for ball, when, where in rows.tolist():
            apexes[int(ball)].append((when, where))
        return apexes
    apexes = []
    for ball in range(balls):  # zipped columns: no list a row
        mine = rows[rows[:, 0] == ball]
        apexes.append(list(zip(mine[:, 1].tolist(), mine[:, 2].tolist(), strict=True)))
    return apexes


def _intervals(rows: np.ndarray) -> list[ContactInterval]:
    """A :class:`ContactInterval` for each row (contact, start, end), its fields written straight
    into the new instance's ``__dict__``: the frozen dataclass's ``__init__`` sets each one
    through ``object.__setattr__``, which took a seventh of the eight-ball drop's time (about
    6 000 intervals to its second apex; docs/performance.md, "Stacks of N balls"). The columns
    are zipped, not the rows listed: a list a row cost a third more. In the order of their
    starts, as the Hertz force's and the two-ball drop's (the kernel lists a contact when it
    ends)."""
    rows = rows[np.argsort(rows[:, 1], kind="stable")]
    intervals = []
    append, new = intervals.append, object.__new__
    columns = rows[:, 0].astype(np.int64).tolist(), rows[:, 1].tolist(), rows[:, 2].tolist()
    for contact, start, end in zip(*columns, strict=True):
        interval = new(ContactInterval)
        fields = interval.__dict__
        fields["contact"], fields["start"], fields["end"] = contact, start, end
        append(interval)
    return intervals


def _linear_states(phases: np.ndarray, stack: Stack, times: np.ndarray) -> StackTrajectory:
    """The exact states at ``times`` from a linear run's recorded phases."""
    heights, speeds, forces = kernel.sample(phases, times, stack.masses, stack.zeta)
    return StackTrajectory(times, heights, speeds, forces)


@contextmanager
def _collector_paused() -> Iterator[None]:
    """Python's cycle collector paused while a run's apexes and contact intervals are built:
    thousands of each (about 6 000 and 7 000 to the eight-ball drop's second apex), each
    tracked, set off collections that promoted them all to the oldest generation, and so a
    full collection of every object the process holds (numba's own, over 100 000) every few
    drops: a sixth of the eight-ball drop's time (docs/performance.md, "Stacks of N balls").
    They hold no cycles."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _solve_hertz(
    name: str,
    stack: Stack,
    apexes_wanted: int,
    t_end: float,
    times: np.ndarray | None,
    dense: bool,
) -> StackResult:
    """The Hertz method ``name`` (:data:`twoball.stacks.hertz.METHODS`), imported when first run:
    it loads scipy's integrator, which the linear force does without."""
    from twoball.stacks import hertz

    return hertz.METHODS[name](stack, apexes_wanted, t_end, times, dense)


# Every method by force, then by name (as :data:`twoball.METHODS` for two balls): one signature,
# solve(stack, apexes_wanted, t_end, times, dense) -> StackResult, on a stack validated for
# that force (check_stack(..., force=...): a Hertz stack's gaps in its own units), with the
# apex count and end time of stop_rule, the sample times (or None) checked, and whether to keep
# the dense output (StackResult.evaluate).
StackSolver = Callable[[Stack, int, float, np.ndarray | None, bool], StackResult]
METHODS: dict[str, dict[str, StackSolver]] = {
    "linear": {"compiled": solve_linear},
    "hertz": {name: partial(_solve_hertz, name) for name in ("compiled", "DOP853")},
}


# The clusters' closed forms of the last few stacks, by masses and damping ratios: a cluster is
# built on first use (an eigenvector form: about 0.1 ms for all of three balls', 1.7 ms for
# eight balls'), so drops of the same balls from other heights or gaps (a sweep, the app) reuse
# them. The kernel holds the GIL, so one store is never filled by two runs at once.
_STORES: dict[bytes, clusters.Clusters] = {}
STORES_KEPT = 8


def _store_for(stack: Stack) -> clusters.Clusters:
    """The cluster store for this stack's balls, the most recently used kept last."""
    key = stack.masses.tobytes() + stack.zeta.tobytes()
    store = _STORES.pop(key, None)
    if store is None:
        store = clusters.new_clusters(stack.balls)
    _STORES[key] = store
    while len(_STORES) > STORES_KEPT:
        del _STORES[next(iter(_STORES))]
    return store
