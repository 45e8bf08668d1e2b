"""What a run measures (docs/model.md, "What is measured"): apexes, contacts, ICM and ratios.

Every solver returns a :class:`Result`; the observables are derived from the apexes and the
contact intervals it found, the same way whatever the method. A stack's
:class:`~twoball.stacks.StackResult` shares them (:class:`Measured`).

**Contacts are numbered, not named** (one representation for two balls and for N): contact 0 is
the floor's, contact i the one between ball i and ball i - 1, so for two balls 1 is the balls'
(:data:`FLOOR`, :data:`BALLS`). ``contacts_first`` is a list by the same numbers, floor first:
``[1, 4]`` for the paper's close-up, one floor contact and four ball contacts before the first
apex. A number indexes the contact forces (the stack's ``trajectory.f[:, c]``) and the list
alike, and the top ball's contact, the paper's count, is ``contacts_first[-1]`` for any N.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from twoball.errors import ParameterError, Status
from twoball.model import Drop, icm_height, is_real_number

FLOOR = 0  # the floor's contact, by number
BALLS = 1  # the two balls' contact (a stack's contact i: ball i on ball i - 1)
UNTIL = {"first": 1, "second": 2}
# A run "until a time" wants no apex limit; the kernel's apex table grows with what it finds.
NO_APEX_LIMIT = 2**62


@dataclass(frozen=True)
class ContactInterval:
    """One interval during which contact ``contact`` pushes: 0 the floor, i ball i on ball i - 1
    (for two balls, 1: the balls)."""

    contact: int
    start: float
    end: float


class RunStats(NamedTuple):
    """What a run took: its phases (the exact solver's closed-form phases, a reference method's
    integrator calls), its steps (certified steps; the integrator's accepted steps) and its root
    evaluations (the exact solver's closed-form release times); None where a method does not
    say."""

    phases: int | None = None
    steps: int | None = None
    root_evaluations: int | None = None


SIDES = ("left", "right")


class Outcome(NamedTuple):
    """What a solver (:func:`twoball.exact.solve`, :func:`twoball.reference.solve`) returns."""

    apex_t: list[float]
    apex_h: list[float]
    contacts: np.ndarray  # rows (contact, start, end)
    end_time: float
    status: Status
    message: str | None  # None on success without remark, else what happened in words
    contacts_first: list[int]  # intervals of each contact (floor first) before the first apex
    # state at any times (and side) -> array (n, 6): x1, x2, v1, v2, f01, f12; None unless
    # asked for; an object holding arrays, never a closure, so that a result pickles
    evaluate: Callable[[np.ndarray, str], np.ndarray] | None
    plot_times: np.ndarray | None  # times that show every contact; None unless asked for
    stats: RunStats = RunStats()


@dataclass(frozen=True)
class Trajectory:
    """Sampled heights, velocities and contact forces of both balls (dimensionless); ``x``,
    ``v`` and ``f`` give them as a stack's trajectory holds them
    (:class:`~twoball.stacks.StackTrajectory`: a column per ball, per contact floor first)."""

    t: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    v1: np.ndarray
    v2: np.ndarray
    f01: np.ndarray
    f12: np.ndarray

    @property
    def x(self) -> np.ndarray:
        """Heights, (len(t), 2): the lower ball's, then the upper ball's."""
        return np.column_stack([self.x1, self.x2])

    @property
    def v(self) -> np.ndarray:
        """Velocities, (len(t), 2), as :attr:`x`."""
        return np.column_stack([self.v1, self.v2])

    @property
    def f(self) -> np.ndarray:
        """Contact forces, (len(t), 2), by contact number: the floor's, then the balls'."""
        return np.column_stack([self.f01, self.f12])


class Measured:
    """What :class:`Result` and :class:`~twoball.stacks.StackResult` share, by the same names and
    types: the top ball's apexes (``apex_t``, ``apex_h``: lists of floats) and the observables
    derived from them, the contact intervals (:class:`ContactInterval`, numbered) and their
    counts before the first apex (``contacts_first``, a list by contact number, floor first),
    how the run ended (``status``, ``reason``, ``success``), what it took (``stats``) and one
    :meth:`summary` whose observables' keys and types are the same for both.

    A subclass provides ``apex_t``, ``apex_h``, ``contacts``, ``contacts_first``, ``status``,
    ``reason``, ``method``, ``x2_0`` (the top ball's height at release) and ``h_icm``.
    """

    apex_t: list[float]
    apex_h: list[float]
    contacts: list[ContactInterval]
    contacts_first: list[int]
    status: Status
    reason: str | None
    method: str

    @property
    def success(self) -> bool:
        """True when the run reached what was asked or the top ball came to rest."""
        return self.status.success

    @property
    def h1(self) -> float | None:
        """Height of the top ball's first apex after release, None if there was none."""
        return self.apex_h[0] if self.apex_h else None

    @property
    def h2(self) -> float | None:
        """Height of the top ball's second apex, None if it does not happen."""
        return self.apex_h[1] if len(self.apex_h) > 1 else None

    @property
    def t1(self) -> float | None:
        return self.apex_t[0] if self.apex_t else None

    @property
    def t2(self) -> float | None:
        return self.apex_t[1] if len(self.apex_t) > 1 else None

    def _ratio(self, name: str) -> float | None:
        h1, h2 = (math.nan if h is None else h for h in (self.h1, self.h2))
        value = float(ratios(np.float64(h1), np.float64(h2), self.x2_0, self.h_icm)[name])
        return None if math.isnan(value) else value

    @property
    def h1_over_icm(self) -> float | None:
        return self._ratio("h1_over_icm")

    @property
    def h1_over_drop(self) -> float | None:
        return self._ratio("h1_over_drop")

    @property
    def h2_over_drop(self) -> float | None:
        return self._ratio("h2_over_drop")

    @property
    def h2_over_h1(self) -> float | None:
        return self._ratio("h2_over_h1")

    @property
    def delayed_rebound(self) -> bool | None:
        """h2 > h1; None when either bounce is missing."""
        return None if self.h1 is None or self.h2 is None else self.h2 > self.h1

    def contacts_per_bounce(self, contact: int = BALLS) -> list[int]:
        """Intervals of contact number ``contact`` that start before each apex of the top ball
        and after the previous one."""
        counts = []
        previous = -math.inf
        for apex in self.apex_t:
            counts.append(
                sum(1 for c in self.contacts if c.contact == contact and previous <= c.start < apex)
            )
            previous = apex
        return counts

    def measured(self) -> dict[str, float | int | str | bool | list[int] | None]:
        """The observables of :meth:`summary` that every result has, by the same keys and types
        (the parameters before them are each model's own)."""
        return {
            "method": self.method,
            "h1": self.h1,
            "h2": self.h2,
            "t1": self.t1,
            "t2": self.t2,
            "contacts_first": list(self.contacts_first),
            "h_icm": self.h_icm,
            "x2_0": self.x2_0,
            "h1_over_icm": self.h1_over_icm,
            "h1_over_drop": self.h1_over_drop,
            "h2_over_drop": self.h2_over_drop,
            "h2_over_h1": self.h2_over_h1,
            "delayed_rebound": self.delayed_rebound,
            "status": self.status.name,
            "reason": self.reason,
        }


@dataclass
class Result(Measured):
    """The outcome of one drop (the shared names and types: :class:`Measured`).

    ``apex_t`` and ``apex_h`` list the upper ball's apexes in free flight (docs/model.md, "What is
    measured"), in order.
    ``status`` says how the run ended (``success`` is True for a run that reached what was asked
    or ended at rest); ``reason`` is None when the run reached what was asked, else why it
    stopped early, in words. ``contacts`` lists every contact interval found, numbered (0: the
    floor, 1: the balls), and ``contacts_first`` counts each before the first apex, ``[floor,
    balls]``; ``trajectory`` is set only when asked (``t_eval`` or ``dense_output``; without
    ``t_eval`` it is sampled at ``plot_times`` when first read, so that a caller who evaluates
    the dense solution at times of its own does not pay for it); :meth:`evaluate` needs
    ``dense_output``.
    """

    drop: Drop
    method: str
    apex_t: list[float]
    apex_h: list[float]
    contacts: list[ContactInterval]
    end_time: float
    reason: str | None = None
    contacts_first: list[int] = field(default_factory=lambda: [0, 0])
    rtol: float | None = None
    atol: float | None = None
    trajectory: Trajectory | None = field(default=None, repr=False)
    status: Status = Status.DONE
    dense: Callable[[np.ndarray, str], np.ndarray] | None = field(
        default=None, repr=False, compare=False
    )
    stats: RunStats = field(default=RunStats(), compare=False)
    plot_times: np.ndarray | None = field(default=None, repr=False, compare=False)

    def evaluate(self, t: np.ndarray | float, side: str = "right") -> Trajectory:
        """The state and forces at times ``t`` (exact at every t for the exact method).

        Parameters
        ----------
        t : float or array
            Dimensionless times; the run must have been made with
            ``simulate(..., dense_output=True)``.
        side : "right" or "left"
            At a switch the contact forces jump (docs/model.md, "Bodies, coordinates, forces"):
            the state just after it ("right", the default) or just before it ("left"). The
            reference methods interpolate continuously, so both sides are the same there.

        Returns
        -------
        Trajectory
            x1, x2, v1, v2 and the two contact forces at those times.

        Examples
        --------
        >>> import twoball
        >>> r = twoball.simulate(0.816, 0.05, 0.3, dense_output=True)
        >>> at = r.evaluate(r.t1)  # the first apex: the upper ball at rest, at height h1
        >>> bool(abs(at.v2[0]) < 1e-9), bool(abs(at.x2[0] - r.h1) < 1e-9 * r.h1)
        (True, True)
        """
        if self.dense is None:
            raise ValueError("evaluate needs a run with dense_output=True")
        if side not in SIDES:
            raise ParameterError(f"side must be 'left' or 'right'; got {side!r}")
        times = as_times("t", t)
        check_span("t", times, self.end_time, self.status is Status.REST and self.method == "exact")
        return trajectory_of(times, self.dense(times, side))

    @property
    def x2_0(self) -> float:
        """Initial height X2(0) of the upper ball."""
        return self.drop.x2_0

    @property
    def h_icm(self) -> float:
        """First apex of the upper ball in the independent contact model."""
        d = self.drop
        return icm_height(d.x1_0, d.x2_0 - d.x1_0, d.eps, d.eps12, d.mu)

    def summary(self) -> dict[str, float | int | str | bool | list[int] | None]:
        """The drop's parameters and the observables as plain values (JSON-ready: None where
        absent)."""
        d = self.drop
        return {
            "eps": d.eps,
            "eps12": d.eps12,
            "mu": d.mu,
            "tau_ratio": d.tau_ratio,
            "height": d.height,
            **self.measured(),
        }


def _sampled_trajectory(self: Result) -> Trajectory | None:
    if self._trajectory is None and self.plot_times is not None:
        self._trajectory = trajectory_of(self.plot_times, self.dense(self.plot_times, "right"))
    return self._trajectory


def _set_trajectory(self: Result, trajectory: Trajectory | None) -> None:
    self._trajectory = trajectory


# (set after the dataclass is made: its __init__ sets the field through the property)
Result.trajectory = property(
    _sampled_trajectory,
    _set_trajectory,
    doc="The state sampled at ``t_eval``, or at ``plot_times`` (sampled when first read).",
)


def as_times(name: str, values: object) -> np.ndarray:
    """``values`` as a one-dimensional array of finite times, or ParameterError naming ``name``
    (strings and booleans are not times)."""
    if isinstance(values, np.ndarray) and values.dtype.kind in "iuf":
        # an array of numbers (the app's sampling grids): checked whole, not item by item,
        # which took most of an evaluate() of 2001 times
        items = np.atleast_1d(values)
        if items.ndim != 1 or items.size == 0:
            raise ParameterError(
                f"{name} must be a non-empty one-dimensional array of finite times"
            )
        if not np.isfinite(items).all():
            bad = items[~np.isfinite(items)][0]
            raise ParameterError(
                f"{name} must be a one-dimensional array of finite times; got {float(bad)!r} in it"
            )
        return items.astype(float)
    items = np.atleast_1d(np.asarray(values, dtype=object))
    if items.ndim != 1 or items.size == 0:
        raise ParameterError(f"{name} must be a non-empty one-dimensional array of finite times")
    for item in items:
        if not is_real_number(item) or not math.isfinite(float(item)):
            raise ParameterError(
                f"{name} must be a one-dimensional array of finite times; got {item!r} in it"
            )
    return items.astype(float)


def check_span(name: str, times: np.ndarray, end_time: float, open_ended: bool) -> None:
    """Refuse times outside the run, [0, end_time]: before the release there is no motion, and
    after the run's end the solution would be extrapolated (a ball in free fall through the
    floor). ``open_ended``: the run ended at a proven rest, whose last phase holds for ever, so
    any later time is the state at rest."""
    low, high = float(times.min()), float(times.max())
    if low < 0.0 and end_time == math.inf:
        raise ParameterError(f"{name} must hold times >= 0 (from the release); got {low:g}")
    # a few ulp of slack: a run to a time ends there up to the rounding of its clock
    if low < 0.0 or (high > end_time + 1e-12 * max(abs(end_time), 1.0) and not open_ended):
        span = f"[0, {end_time:.10g}]" if not open_ended else "[0, inf) (the run ended at rest)"
        got = f"{low:g}" if low == high else f"times from {low:g} to {high:g}"
        raise ParameterError(
            f"{name} must lie within the run's time span {span}; got {got} (run further with "
            "until=... to sample later times)"
        )


def relative_error(value, reference_value) -> float:
    """|value - reference| / |reference| of one observable of two runs, the one rule for every
    comparison: inf when only one of them has the value (a missed or an invented bounce) or the
    value is not finite, NaN when neither has it (there is no such bounce to compare).

    >>> relative_error(3.3, 3.0) < 0.11, relative_error(None, 3.0), relative_error(None, None)
    (True, inf, nan)
    """
    if reference_value is None:
        return math.nan if value is None else math.inf
    if value is None or not math.isfinite(value):
        return math.inf
    return float(abs(value - reference_value) / abs(reference_value))


def ratios(h1, h2, x2_0, h_icm) -> dict:
    """The four ratios of docs/model.md, "What is measured": h1/h_ICM, h1/X2(0), h2/X2(0) and
    h2/h1, elementwise on numbers or arrays (NaN in, NaN out where a bounce is missing)."""
    return {
        "h1_over_icm": h1 / h_icm,
        "h1_over_drop": h1 / x2_0,
        "h2_over_drop": h2 / x2_0,
        "h2_over_h1": h2 / h1,
    }


def trajectory_of(times: np.ndarray, values: np.ndarray) -> Trajectory:
    """A :class:`Trajectory` from times and rows (x1, x2, v1, v2, f01, f12)."""
    return Trajectory(times, *(np.ascontiguousarray(values[:, i]) for i in range(6)))


def contact_intervals(rows: np.ndarray) -> list[ContactInterval]:
    """Contact intervals from rows (contact, start, end), sorted by start."""
    intervals = [ContactInterval(int(c), s, e) for c, s, e in np.asarray(rows).tolist()]
    return sorted(intervals, key=lambda interval: interval.start)


def stop_rule(until: str | float) -> tuple[int, float]:
    """(apexes wanted, end time) for an ``until`` argument."""
    if isinstance(until, str):
        if until not in UNTIL:
            raise ParameterError(f"until must be 'first', 'second' or a time > 0; got {until!r}")
        return UNTIL[until], math.inf
    if not is_real_number(until):  # a boolean or bytes is no time
        raise ParameterError(f"until must be 'first', 'second' or a time > 0; got {until!r}")
    t_end = float(until)
    if not (math.isfinite(t_end) and t_end > 0.0):
        raise ParameterError(f"until must be 'first', 'second' or a finite time > 0; got {until!r}")
    return NO_APEX_LIMIT, t_end
