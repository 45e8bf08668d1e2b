"""A stack of N balls: its validated parameters (:func:`check_stack`), the ICM chain, the apex
bound, and what a run of it returns (:class:`StackResult`; docs/model.md, "Stacks of N balls")."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from twoball.errors import ParameterError, Status
from twoball.model import (
    DEFAULT_HEIGHT,
    MASS_RATIO_RANGE,
    RESOLUTION,
    chain_rounding_ratio,
    check_value,
    decay_ratio,
    domain_error,
    floor_contact_time,
    icm_meeting,
    upper_after_collision,
)
from twoball.observables import ContactInterval, Measured, RunStats, as_times, check_span

MAX_BALLS = 16


# With this many balls or more, gaps below SMALLEST_GAP were seen to stall the solver (measured:
# five to eight balls of any mass ratio with gaps of 1e-12 and less; four near-elastic balls
# released touching at H = 10). Three balls carry a zero gap: 576 drops over eps 0.3-1,
# H 10-1e5 and mass ratios 0.01-10 all finish.
# (the linear force's: a Hertz contact's force is continuous at first touch, and its step bounds a
# touching contact by its own force only; touching Hertz stacks of 4 to 6 balls finish)
TOUCHING_LIMIT_BALLS = 4


SMALLEST_GAP = 1e-9


HERTZ_SMALLEST_RESTITUTION = 0.05  # below it the Hunt-Crossley clamp chatters


# The largest Hunt-Crossley damping lam (the contacts' settling speed is of order 1): measured at
# eps = 0.9 with two balls, lam = 3.7 (H = 1e-3) takes 0.2 s, 37 (1e-5) 1 s, 372 (1e-7) 22 s,
# 3700 (1e-9) runs out of steps after 50 s; eps = 0.05 at H = 1e-3 (lam 450) takes 85 s.
HERTZ_LARGEST_DAMPING = 50.0


# The heaviest ball relative to ball 0 with the Hertz force: 1e4 takes 4 s, 1e6 runs out of
# steps after 60 s (the light ball 0 rings fast under it).
HERTZ_LARGEST_MASS = 1e4


FORCES = ("linear", "hertz")


@dataclass(frozen=True)
class Stack:
    """A validated stack (docs/model.md, "Stacks of N balls"): masses relative to ball 0, the
    restitution and damping ratio of each contact (floor first), the gaps, the floor contact
    time and the heights at release."""

    mass_ratios: tuple[float, ...]
    eps: tuple[float, ...]
    tau_ratios: tuple[float, ...]
    height: float
    masses: np.ndarray = field(repr=False)
    zeta: np.ndarray = field(repr=False)
    tau_f: float = field(repr=False)
    x_start: np.ndarray = field(repr=False)

    @property
    def balls(self) -> int:
        """N, the number of balls."""
        return len(self.masses)


def _checked(declared: str, shown: str, value: object) -> float:
    """``value`` checked against the declared range of ``declared``, errors naming ``shown``."""
    try:
        return check_value(declared, value, text=False)
    except ParameterError as error:
        raise ParameterError(str(error).replace(declared, shown, 1)) from None


def _refuse_unordered(name: str, values: object) -> None:
    """Refuse a set or an iterator for ``name``: the balls are in order, from the floor up, and
    a set has none (a generator is read once); a ParameterError naming ``name``. (They were
    taken as one item and reported as ``name[0]``, not a number.)"""
    if isinstance(values, (set, frozenset, Iterator)):
        raise ParameterError(
            f"{name} must be one number or a flat sequence (a list, tuple or array, the balls "
            f"from the floor up); got a {type(values).__name__}"
        )


def _values(name: str, declared: str, values: object, count: int, what: str) -> list[float]:
    """A declared parameter given as one number (every one alike) or as a flat sequence of
    exactly ``count`` values, checked. A sequence of another length is refused, one of one
    value too when ``count`` is more: it is not taken for every one (a list that lost entries)."""
    _refuse_unordered(name, values)
    try:
        items = np.asarray(values, dtype=object)
    except (TypeError, ValueError):  # not array-like: checked (and refused) as one number
        return [_checked(declared, name, values)] * count
    if items.ndim == 0:
        return [_checked(declared, name, values)] * count
    if items.ndim > 1 or len(items) != count:
        raise ParameterError(
            f"{name} must be one number or a flat sequence of exactly {count} ({what}); got "
            f"{'a nested sequence' if items.ndim > 1 else f'a sequence of {len(items)}'}"
        )
    return [_checked(declared, f"{name}[{i}]", item) for i, item in enumerate(items)]


def check_stack(
    mass_ratios: object,
    eps: object,
    tau_ratios: object,
    *,
    height: float = DEFAULT_HEIGHT,
    force: str = "linear",
) -> Stack:
    """Validate a stack's inputs with the two-ball model's ranges and derive the rest.

    ``mass_ratios`` holds the N - 1 ratios m_i / m_(i-1) (each a ``mu``); ``eps`` one restitution
    or a sequence of N (the floor's, then each pair's); ``tau_ratios`` one gap or a sequence of
    N - 1 (each a ``tau_ratio``, the delay td_i over the floor contact time): a sequence of
    another length is refused, not shared out. ``force`` the contact law, which sets the
    smallest gap (:data:`TOUCHING_LIMIT_BALLS`) and, for Hertz, the smallest eps. Raises
    ``ParameterError`` (a ``ValueError``) naming the parameter and its allowed range.

    The stack's ``tau_f`` (the floor contact time that measures the gaps) and release heights
    ``x_start`` are ``force``'s own: the Hertz floor contact time for ``force="hertz"``
    (docs/stacks.md), so that the stack is the one a run of that force starts from
    (``simulate_stack(...).stack``) and :func:`icm_chain` of it is the run's h_ICM. ``zeta`` is
    the linear dashpots' (a Hertz run calibrates its own damping).
    """
    if force not in FORCES:
        raise ParameterError(f"force must be one of {', '.join(FORCES)}; got {force!r}")
    _refuse_unordered("mass_ratios", mass_ratios)
    try:
        given = np.asarray(mass_ratios, dtype=object)
    except (TypeError, ValueError):
        given = np.empty(1, dtype=object)
        given[0] = mass_ratios  # (its own check says what is wrong with it)
    if given.ndim > 1:  # (flattened, [[0.2, 0.3], [0.4, 0.5]] was taken for five balls')
        raise ParameterError(
            "mass_ratios must be one number or a flat sequence of 1 to "
            f"{MAX_BALLS - 1} values; got a nested sequence"
        )
    ratios = list(np.atleast_1d(given))
    if not 1 <= len(ratios) <= MAX_BALLS - 1:
        raise ParameterError(
            f"mass_ratios must hold 1 to {MAX_BALLS - 1} values (N = 2 to {MAX_BALLS} balls); "
            f"got {len(ratios)}"
        )
    ratios = [_checked("mu", f"mass_ratios[{i}]", value) for i, value in enumerate(ratios)]
    balls = len(ratios) + 1
    restitutions = _values(
        "eps", "eps", eps, balls, f"the floor's, then each pair's: {balls} balls"
    )
    gaps = _values("tau_ratios", "tau_ratio", tau_ratios, balls - 1, f"one per pair: {balls} balls")
    height = check_value("height", height, text=False)
    masses = np.cumprod([1.0, *ratios])
    low, high = MASS_RATIO_RANGE
    if masses.min() < low or masses.max() > high:
        raise ParameterError(
            "the masses relative to ball 0 (products of mass_ratios) must lie in "
            f"[{low:g}, {high:g}]; got {masses.min():.3g} to {masses.max():.3g}"
        )
    if force == "linear" and balls >= TOUCHING_LIMIT_BALLS and min(gaps) < SMALLEST_GAP:
        raise ParameterError(
            f"tau_ratios must be at least {SMALLEST_GAP:g} with {TOUCHING_LIMIT_BALLS} or more "
            f"balls and the linear force; got {min(gaps):g}. Balls released touching pass the "
            "first impact's compression up the stack as a contact flatter than rounding, which "
            "the solver cannot follow (docs/stacks.md, Limits)"
        )
    if force == "hertz" and min(restitutions) < HERTZ_SMALLEST_RESTITUTION:
        raise ParameterError(
            f"eps must be at least {HERTZ_SMALLEST_RESTITUTION:g} with the hertz force "
            f"(tested range [{HERTZ_SMALLEST_RESTITUTION:g}, 1]); got {min(restitutions):g}"
        )
    if force == "hertz":
        if masses.max() > HERTZ_LARGEST_MASS:
            raise ParameterError(
                "the masses relative to ball 0 (products of mass_ratios) must lie in "
                f"[{low:g}, {HERTZ_LARGEST_MASS:g}] with the hertz force; got up to "
                f"{masses.max():.3g} (heavier, the light balls below ring too fast to follow: "
                "docs/stacks.md, Limits)"
            )
        _check_hertz_damping(masses, restitutions, height)
    zeta = np.empty(balls)
    zeta[0] = decay_ratio(restitutions[0])
    for i in range(1, balls):
        reduced = masses[i - 1] * masses[i] / (masses[i - 1] + masses[i])
        zeta[i] = decay_ratio(restitutions[i]) * math.sqrt(reduced)
    if force == "hertz":
        from twoball.stacks import hertz_contact  # scipy: imported with the Hertz force only

        tau_f = hertz_contact.floor_contact_time(restitutions[0], height)
    else:
        tau_f = floor_contact_time(zeta[0])
    x_start = release_heights(height, gaps, tau_f)
    _check_domain(ratios, masses, restitutions, gaps, height, force, tau_f, x_start)
    return Stack(
        tuple(ratios), tuple(restitutions), tuple(gaps), height, masses, zeta, tau_f, x_start
    )


def _check_hertz_damping(masses, restitutions, height) -> None:
    """Refuse a Hertz stack whose Hunt-Crossley damping, calibrated at its impact speeds, is
    above :data:`HERTZ_LARGEST_DAMPING` (a slow impact: the contacts then settle overdamped, too
    slowly to follow). lam scales as 1/sqrt(H), so the message gives the smallest height."""
    from twoball.stacks import hertz_contact as hertz  # scipy: imported with the Hertz force only

    eps = np.asarray(restitutions, dtype=float)
    speeds = hertz.calibration_speeds(masses, eps, height)
    factors = np.array([hertz.damping_factor(float(e)) for e in eps])
    with np.errstate(divide="ignore"):
        lam = float(np.max(np.where(factors > 0.0, factors / speeds, 0.0)))
    if lam <= HERTZ_LARGEST_DAMPING:
        return
    smallest = height * (lam / HERTZ_LARGEST_DAMPING) ** 2
    raise ParameterError(
        f"height must be at least {smallest:.3g} for eps = {', '.join(f'{e:g}' for e in eps)} "
        f"with the hertz force (got {height:g}): at a slower impact the Hunt-Crossley damping "
        f"calibrated to eps (lam = Lambda(eps)/v, here up to {lam:.3g}, at most "
        f"{HERTZ_LARGEST_DAMPING:g}) overdamps the contacts' settling, which the solver cannot "
        "follow in its step budget (docs/stacks.md, Limits)"
    )


def _check_domain(ratios, masses, restitutions, gaps, height, force, tau_f, x_start) -> None:
    """Refuse a stack beyond the domain double precision can carry, as ``simulate`` refuses a
    drop (docs/model.md, "Stacks of N balls", the domain): the rounding of the top ball's
    height at release, over the smallest contact overlap, at most :data:`RESOLUTION`."""
    if chain_rounding_ratio(height, masses, x_start[-1], force) <= RESOLUTION:
        return
    shown = ", ".join(f"{r:g}" for r in ratios)
    raise ParameterError(
        domain_error(
            height,
            masses,
            sum(gaps) * tau_f,
            tau_f,
            gap_name="tau_ratios (their sum)" if len(gaps) > 1 else "tau_ratios",
            masses_text=f"mass_ratios = [{shown}]"
            + (" and the hertz force" if force == "hertz" else ""),
            force=force,
        )
    )


def release_heights(height: float, tau_ratios: tuple[float, ...], tau_f: float) -> np.ndarray:
    """X_i at release: (sqrt(H) + sum_(j<i) td_j / sqrt(2))^2 with td_j = tau_ratio_j tau_f."""
    delays = np.concatenate([[0.0], np.cumsum(tau_ratios)]) * tau_f
    with np.errstate(over="ignore"):  # (inf for an absurd gap: the domain check refuses it,
        return (math.sqrt(height) + delays / math.sqrt(2.0)) ** 2  # its warning a second line)


@dataclass
class StackTrajectory:
    """Sampled heights, velocities (len(t), N) and contact forces (len(t), N; floor first)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    f: np.ndarray


@dataclass
class StackResult(Measured):
    """The outcome of one stack drop, with :class:`twoball.Result`'s names and types
    (:class:`~twoball.observables.Measured`): the top ball's apexes ``apex_t``, ``apex_h`` (and
    ``h1``, ``h2``, ...), the contact intervals numbered (0: the floor, i: ball i on ball i - 1)
    and ``contacts_first`` by the same numbers, how the run ended; and every ball's apexes in
    free flight (``apexes``). :meth:`evaluate` needs ``dense_output``."""

    stack: Stack
    force: str
    apexes: list[list[tuple[float, float]]]  # per ball: (t, height) of each apex
    contacts: list[ContactInterval]
    contacts_first: list[int]  # intervals of each contact (floor first) that start before h1
    end_time: float
    status: Status
    method: str = "compiled"
    trajectory: StackTrajectory | None = field(default=None, repr=False)
    reason: str | None = None  # None when the run reached what was asked, else why not
    stats: RunStats = field(default=RunStats(), compare=False)
    dense: Callable[[np.ndarray], StackTrajectory] | None = field(
        default=None, repr=False, compare=False
    )

    def evaluate(self, t: np.ndarray | float) -> StackTrajectory:
        """The heights, velocities and forces at times ``t`` within the run, from its dense
        output (``simulate_stack(..., dense_output=True)``): exact for the linear force (its
        closed forms); for the Hertz force the cubics between its steps' ends
        (:func:`twoball.stacks.hertz.between_nodes`, docs/stacks.md, "How each force is
        solved"). A run sampled once its end is known, with no second run.

        >>> from twoball.stacks import simulate_stack
        >>> r = simulate_stack([0.2, 0.2], 0.9, 0.2, force="hertz", dense_output=True)
        >>> bool(abs(r.evaluate(r.apex_t[0]).x[0, 2] - r.h1) < 1e-9 * r.h1)
        True
        """
        if self.dense is None:
            raise ValueError("evaluate needs a run with dense_output=True")
        times = as_times("t", t)
        at_rest = self.status is Status.REST
        if at_rest and self.force == "hertz" and float(times.max()) > self.end_time:
            # (its balls still quiver in their contacts after the proof that none flies again,
            # and its cubics end with the run: t_eval carries the integration on)
            raise ParameterError(
                f"t must lie within the run's time span [0, {self.end_time:.10g}] for the Hertz "
                "force's dense output, which ends at the proven rest; sample later times with "
                "t_eval=..."
            )
        # after a linear stack's proven rest every later time is that rest (as t_eval, and
        # the two-ball Result.evaluate): they were refused, with a hint that could not help
        check_span("t", times, self.end_time, at_rest)
        return self.dense(times)

    @property
    def apex_t(self) -> list[float]:
        """The times of the top ball's apexes (as :attr:`twoball.Result.apex_t`)."""
        return [t for t, _ in self.apexes[-1]]

    @property
    def apex_h(self) -> list[float]:
        """The heights of the top ball's apexes (as :attr:`twoball.Result.apex_h`)."""
        return [h for _, h in self.apexes[-1]]

    @property
    def x2_0(self) -> float:
        """The top ball's height at release (as :attr:`twoball.Result.x2_0`)."""
        return float(self.stack.x_start[-1])

    @property
    def h_icm(self) -> float:
        """The ICM chain's height for the top ball (:func:`icm_chain`)."""
        return icm_chain(self.stack)[-1]

    def summary(self) -> dict[str, object]:
        """The stack's parameters and the observables as plain values (JSON-ready: None where
        absent; the observables' keys and types as :meth:`twoball.Result.summary`'s), with
        every ball's first apex."""
        stack = self.stack
        return {
            "balls": stack.balls,
            "mass_ratios": list(stack.mass_ratios),
            "eps": list(stack.eps),
            "tau_ratios": list(stack.tau_ratios),
            "height": stack.height,
            "force": self.force,
            **self.measured(),
            "first_apexes": [apexes[0][1] if apexes else None for apexes in self.apexes],
        }


def _apex_bound(stack: Stack, force: str) -> float:
    """The highest the top ball can fly: the energy at release, sum m_i X_i(0), plus the most
    the balls below and their contacts can give by sinking: each contact c below the top pair,
    carrying the weight W_c of the balls above it but under the top, holds at least
    -W_c^2/2 (linear: -W delta + delta^2/2) or -(3/5) W_c^(5/3) (Hertz). For two balls this
    is :func:`twoball.model.apex_bound`."""
    below = stack.masses[:-1]
    weights = np.cumsum(below[::-1])[::-1]
    sink = 0.5 * weights**2 if force == "linear" else 0.6 * weights ** (5.0 / 3.0)
    energy = float((stack.masses * stack.x_start).sum() + sink.sum())
    return energy / stack.masses[-1]


def icm_chain(stack: Stack) -> list[float]:
    """The textbook chain of independent collisions (docs/model.md, "Stacks of N balls").

    Ball 0 hits the floor at sqrt(2H) and leaves with eps_0 times it; then ball i, released at
    X_i(0) and falling freely, meets ball i - 1 where that one flies after its own collision
    (both fall alike, so the distance between them closes at a constant speed), with
    restitution eps_i. Returns each ball's apex after its collision, in its own coordinate X_i:
    the collision's height plus v^2/2. Released touching (no gaps), every collision is at
    height 0: for an elastic three-ball stack with vanishing mass ratios the top ball leaves at
    7 sqrt(2H), 49 times as high. Ball 1 meets ball 0 on a later bounce when the gap is large
    (:func:`twoball.model.icm_meeting`). For two balls this is h_ICM of "What is measured" with
    the gap X_1(0) - H (:func:`twoball.model.icm_height`); the gaps had been left out, and a
    two-ball stack's h_ICM differed from the same drop's (h1/h_ICM 0.948 against 1.016 at
    tau_ratio 10).
    """
    if not isinstance(stack, Stack):
        raise ParameterError(
            f"stack must be a Stack, made by check_stack(mass_ratios, eps, tau_ratios, ...) "
            f"or a StackResult's .stack; got {type(stack).__name__}"
        )
    clock = math.sqrt(2.0 * stack.height)  # (g = 1: the time of the floor impact, and its speed)
    level, up = 0.0, stack.eps[0] * clock  # ball i - 1 leaving its collision: height, speed
    heights = [up * up / 2.0]
    for i in range(1, stack.balls):
        below, mass = stack.masses[i - 1], stack.masses[i]
        if i == 1:  # ball 0 bounces on the floor until ball 1 arrives (icm_meeting)
            gap = float(stack.x_start[1]) - stack.height
            clock, level, below_speed = icm_meeting(stack.height, gap, stack.eps[0])
        else:  # ball i falls at -clock: the distance to ball i - 1 closes at up + clock
            apart = float(stack.x_start[i]) - clock * clock / 2.0 - level
            flight = apart / (up + clock)
            level += up * flight - flight * flight / 2.0
            clock += flight
            below_speed = up - flight
        up = upper_after_collision(below_speed, -clock, stack.eps[i], mass / below)
        heights.append(float(level + up * up / 2.0))  # Python floats, as Result.h_icm
    return heights
