"""The two-ball model: parameters, restitution and damping, initial condition (docs/model.md).

Everything here is plain physics: no solver, no UI. Parameters are declared once, in
:class:`Parameters`, with their bounds and documentation; :func:`check_parameters` validates plain
floats against those same declarations, so the library, the command line and the app share one
definition of what is allowed.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
import param

from twoball.errors import ParameterError
from twoball.jit import njit

DEFAULT_HEIGHT = 1.0e4

# The domain double precision can carry (docs/model.md, "The domain double precision can carry").
# Measured, not derived: outside these the solver was seen to stall or to break the energy bound.
SMALLEST_RESTITUTION = 0.01
MASS_RATIO_RANGE = (1e-9, 1e6)
# The largest rounding of the heights, relative to the contacts' overlap, that is accepted:
# h1 and h2 then carry a relative error of about ten times this.
RESOLUTION = 1e-6
MACHINE_EPSILON = 2.220446049250313e-16


class Parameters(param.Parameterized):
    """The inputs of one drop (docs/model.md, "Bodies, coordinates, forces" and "Initial
    condition")."""

    eps = param.Number(
        0.816,
        bounds=(SMALLEST_RESTITUTION, 1.0),
        doc="Coefficient of restitution of the floor contact (eps01); also of the ball contact "
        "unless eps12 is given.",
    )
    eps12 = param.Number(
        None,
        allow_None=True,
        bounds=(SMALLEST_RESTITUTION, 1.0),
        doc="Coefficient of restitution of the ball-ball contact; None means equal to eps.",
    )
    mu = param.Number(
        0.05,
        bounds=MASS_RATIO_RANGE,
        doc="Mass ratio m2/m1 (upper over lower ball).",
    )
    tau_ratio = param.Number(
        0.3,
        bounds=(0.0, None),
        doc="tau_d/tau_f: delay between the balls' arrivals over the floor contact time.",
    )
    height = param.Number(
        DEFAULT_HEIGHT,
        bounds=(0.0, None),
        inclusive_bounds=(False, True),
        doc="Dimensionless drop height H = h k / (m1 g) of the lower ball.",
    )


def _declared_bounds(name: str) -> tuple[float | None, float | None, bool, bool]:
    """(low, high, low closed, high closed) as declared on :class:`Parameters`."""
    declared = Parameters.param[name]
    return (*declared.bounds, *declared.inclusive_bounds)


# Read once from the declarations: validation runs for every simulated drop.
_BOUNDS = {name: _declared_bounds(name) for name in ("eps", "eps12", "mu", "tau_ratio", "height")}


def allowed_range(name: str) -> str:
    """The allowed range of a declared parameter, written as an interval (the one source for
    error messages, docstrings and the command line's help)."""
    low, high, low_closed, high_closed = _BOUNDS[name]
    left = ("[" if low_closed else "(") + ("-inf" if low is None else f"{low:g}")
    closing = "]" if high_closed and high is not None else ")"
    right = ("inf" if high is None else f"{high:g}") + closing
    return f"{left}, {right}"


def with_ranges(function):
    """Write the declared ranges into ``function``'s docstring: each ``RANGE(name)`` becomes
    :func:`allowed_range` of that parameter, so the documentation cannot drift from the
    declarations."""
    doc = function.__doc__ or ""
    for name in _BOUNDS:
        doc = doc.replace(f"RANGE({name})", allowed_range(name))
    function.__doc__ = doc
    return function


def check_value(name: str, value: object, *, text: bool = True) -> float:
    """Return ``value`` as a float if it lies in the declared range of ``name``, else raise.

    Raises ``ValueError`` naming the parameter and its allowed range (NaN and infinities included).
    A boolean is never a number here (True is not a restitution of 1). ``text``: a string is
    parsed as a number (what a URL or a typed field holds: the app's case); with False (the
    library's entry points, :func:`check_parameters`, ``simulate_stack``) a real number is
    required, a Python or numpy int or float, and '0.9' is refused.
    """
    if isinstance(value, (str, bytes, np.str_)) and text:
        try:
            number = float(value)
        except ValueError:
            raise ParameterError(
                f"{name} must be a number in {allowed_range(name)}; got {value!r}"
            ) from None
    elif is_real_number(value):
        number = float(value)  # type: ignore[arg-type]
    else:
        raise ParameterError(
            f"{name} must be a real number in {allowed_range(name)} (not text or a boolean); "
            f"got {value!r}"
        )
    low, high, low_closed, high_closed = _BOUNDS[name]
    ok = math.isfinite(number)
    if ok and low is not None:
        ok = number >= low if low_closed else number > low
    if ok and high is not None:
        ok = number <= high if high_closed else number < high
    if not ok:
        raise ParameterError(
            f"{name} must be a finite number in {allowed_range(name)}; got {value!r}"
        )
    return number


def check_flag(name: str, value: object) -> bool:
    """A switch of the library's entry points (``dense_output``, ``throw``...): True or False
    (Python's or numpy's); anything else is refused, naming it ('no' had been taken as true)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ParameterError(f"{name} must be True or False; got {value!r}")


def is_real_number(value: object) -> bool:
    """True for a real number: an int or float of Python or numpy (or a 0-d array of one), not a
    string, bytes or a boolean."""
    if type(value) is float or type(value) is int:  # the common case, without the ABC checks
        return True
    if isinstance(value, (bool, np.bool_, str, bytes)):
        return False
    if isinstance(value, np.ndarray):
        return value.ndim == 0 and value.dtype.kind in "iuf"
    return isinstance(value, (numbers.Real, np.integer, np.floating))


@dataclass(frozen=True)
class Drop:
    """A validated drop: the parameters and everything derived from them (docs/model.md,
    "Restitution and damping" and "Initial condition").

    ``zeta01`` and ``zeta12`` are the damping ratios of the two contacts, ``tau_f`` the floor
    contact time, ``x1_0`` and ``x2_0`` the initial heights.
    """

    eps: float
    eps12: float
    mu: float
    tau_ratio: float
    height: float
    zeta01: float
    zeta12: float
    tau_f: float
    x1_0: float
    x2_0: float


@with_ranges
def check_parameters(
    eps: float,
    mu: float,
    tau_ratio: float,
    *,
    eps12: float | None = None,
    height: float = DEFAULT_HEIGHT,
) -> Drop:
    """Validate the inputs of one drop and derive damping, contact time and initial state.

    Parameters
    ----------
    eps, eps12 : float
        Restitution of the floor and of the ball contact, in RANGE(eps); ``eps12`` defaults to
        eps.
    mu : float
        Mass ratio m2/m1 in RANGE(mu).
    tau_ratio : float
        tau_d/tau_f in RANGE(tau_ratio).
    height : float
        Dimensionless drop height H in RANGE(height).

    A drop must also lie in the domain double precision can carry (docs/model.md), which
    bounds the height and the gap together.

    Returns
    -------
    Drop
        The parameters with zeta01, zeta12 (docs/model.md, "Restitution and damping"), tau_f
        and the initial heights (docs/model.md, "Initial condition").

    Raises
    ------
    ParameterError
        A ``ValueError`` naming the parameter and its allowed range.

    Examples
    --------
    The check values of docs/model.md, "Restitution and damping":

    >>> drop = check_parameters(0.816, 0.05, 0.3)
    >>> round(drop.zeta01, 13), round(drop.tau_f, 11)
    (0.0674788868542, 3.0134006872)
    >>> check_parameters(1.5, 0.05, 0.3)
    Traceback (most recent call last):
    ...
    twoball.errors.ParameterError: eps must be a finite number in [0.01, 1]; got 1.5
    """
    eps = check_value("eps", eps, text=False)
    eps12 = eps if eps12 is None else check_value("eps12", eps12, text=False)
    mu = check_value("mu", mu, text=False)
    tau_ratio = check_value("tau_ratio", tau_ratio, text=False)
    height = check_value("height", height, text=False)
    zeta01, zeta12 = damping_ratios(eps, eps12, mu)
    tau_f = floor_contact_time(zeta01)
    x2_0 = initial_gap_height(height, tau_ratio * tau_f)
    if rounding_ratio(height, mu, x2_0) > RESOLUTION:
        raise ParameterError(_outside_domain(mu, tau_ratio, height, tau_f))
    return Drop(eps, eps12, mu, tau_ratio, height, zeta01, zeta12, tau_f, height, x2_0)


def rounding_ratio(height: float, mu: float, x2_0: float) -> float:
    """Rounding of the heights relative to the smallest lengths the drop must resolve
    (docs/model.md, "The domain double precision can carry"): machine epsilon times the largest
    height, over the smaller of the two contacts' typical overlaps (impact or static
    compression), and at least 1e-3 times the rounding relative to the floor's static
    compression (1), which the balls' last, gentle contacts and their rest depend on."""
    return chain_rounding_ratio(height, (1.0, mu), x2_0)


def contact_overlaps(height: float, masses, force: str = "linear") -> list[float]:
    """Each contact's typical overlap in a stack of balls with these masses (ball 0's is 1),
    floor first (docs/model.md, "The domain double precision can carry" and "Stacks of N
    balls"): the larger of its compression at an impact at sqrt(2H) and its static compression.
    Linear: the impact's is sqrt(2H m) with m the contact's reduced mass, the static one the
    weight above it; Hertz: (5/4 m 2H)^(2/5) and that weight to the 2/3. The floor's static
    compression is taken as 1 (ball 0's own weight), as for two balls."""
    masses = [float(m) for m in masses]
    overlaps = []
    for c in range(len(masses)):
        reduced = 1.0 if c == 0 else masses[c - 1] * masses[c] / (masses[c - 1] + masses[c])
        weight = 1.0 if c == 0 else sum(masses[c:])
        if force == "hertz":
            impact = (1.25 * reduced * 2.0 * height) ** 0.4
            static = weight ** (2.0 / 3.0)
        else:
            impact = math.sqrt(2.0 * height * reduced)
            static = weight
        overlaps.append(max(impact, static))
    return overlaps


def chain_rounding_ratio(height: float, masses, x_top: float, force: str = "linear") -> float:
    """:func:`rounding_ratio` for a stack of balls (docs/model.md, "Stacks of N balls"): machine
    epsilon times the highest ball's height at release, over the smallest contact overlap
    (:func:`contact_overlaps`), and at least 1e-3 times it relative to the floor's static
    compression. For two balls, masses (1, mu), it is :func:`rounding_ratio`."""
    smallest = min(contact_overlaps(height, masses, force))
    return MACHINE_EPSILON * max(x_top, 1.0) * max(1.0 / smallest, 1e-3)


def _outside_domain(mu: float, tau_ratio: float, height: float, tau_f: float) -> str:
    """The error for a drop beyond :data:`RESOLUTION`: the largest height, or gap, allowed."""
    return domain_error(
        height,
        (1.0, mu),
        tau_ratio * tau_f,
        tau_f,
        gap_name="tau_ratio",
        masses_text=f"mu = {mu:g}",
    )


def domain_error(
    height: float,
    masses,
    delay: float,
    tau_f: float,
    *,
    gap_name: str,
    masses_text: str,
    force: str = "linear",
) -> str:
    """The error for a drop (or stack) beyond :data:`RESOLUTION`: the largest height allowed
    with the balls released touching, or, where the gap is what raises the top ball too high,
    the largest gap (``delay`` is the top ball's total delay, sum td_i)."""
    where = 'docs/model.md, "The domain double precision can carry"'
    if chain_rounding_ratio(height, masses, height, force) > RESOLUTION:
        low, high = -300.0, 300.0  # log10 of the height: the ratio grows with it at no gap
        for _ in range(80):
            middle = 0.5 * (low + high)
            if chain_rounding_ratio(10.0**middle, masses, 10.0**middle, force) > RESOLUTION:
                high = middle
            else:
                low = middle
        return (
            f"height must be at most {10.0**low:.3g} for {masses_text} (got {height:g}): beyond "
            f"it double precision cannot resolve the contacts ({where})"
        )
    top_max = RESOLUTION / chain_rounding_ratio(height, masses, 1.0, force)  # linear in X_top
    gap_max = math.sqrt(2.0) * (math.sqrt(top_max) - math.sqrt(height)) / tau_f
    return (
        f"{gap_name} must be at most {gap_max:.3g} for height = {height:g} and {masses_text} "
        f"(got {delay / tau_f:g}): beyond it double precision cannot resolve the contacts "
        f"({where})"
    )


# An apex above the energy bound by more than this (relative) is a failed run, not a value.
APEX_BOUND_SLACK = 1e-9


def beyond_bound(height: float, bound: float) -> bool:
    """Whether an apex is not finite or above what the energy at release allows (``bound``:
    :func:`apex_bound`, or the stack's), beyond :data:`APEX_BOUND_SLACK`."""
    return not math.isfinite(height) or height > bound * (1.0 + APEX_BOUND_SLACK)


def apex_bound(drop: Drop) -> float:
    """The highest apex the energy at release allows the upper ball (docs/model.md, "The
    domain double precision can carry"): X2(0) + (X1(0) + 1/2) / mu."""
    return drop.x2_0 + (drop.x1_0 + 0.5) / drop.mu


def restitution(r: float) -> float:
    """Coefficient of restitution of one clamped contact (docs/model.md, "Restitution and
    damping"), on both damping branches.

    Parameters
    ----------
    r : float
        Decay ratio beta/w0 >= 0 (0 elastic, 1 critical damping).

    Returns
    -------
    float
        eps(r) in (0, 1]; eps(1) = exp(-2).

    Examples
    --------
    >>> from twoball.model import decay_ratio, restitution
    >>> restitution(0.0), round(restitution(1.0), 6)
    (1.0, 0.135335)
    >>> abs(restitution(decay_ratio(0.816)) - 0.816) < 1e-15
    True
    """
    if r < 0.0 or not math.isfinite(r):
        raise ParameterError(f"r must be a finite number in [0, inf); got {r!r}")
    if r < 1.0:
        return math.exp(-r / math.sqrt(1.0 - r * r) * math.acos(2.0 * r * r - 1.0))
    if r == 1.0:
        return math.exp(-2.0)
    return math.exp(-r / math.sqrt(r * r - 1.0) * math.acosh(2.0 * r * r - 1.0))


@njit
def _log_restitution(r: float) -> float:
    """-log eps(r), smooth and increasing in r; equal to 2 at r = 1 from both sides."""
    if r < 1.0:
        return r / math.sqrt(1.0 - r * r) * math.acos(2.0 * r * r - 1.0)
    if r == 1.0:
        return 2.0
    return r / math.sqrt(r * r - 1.0) * math.acosh(2.0 * r * r - 1.0)


def decay_ratio(eps: float) -> float:
    """The decay ratio that gives a restitution: the inverse of :func:`restitution`
    (docs/model.md, "Restitution and damping").

    Solved on -log eps, which is increasing in r, by bisection to the last bit; the two branches
    join continuously at r = 1, so bisection is safe across the switch.

    Parameters
    ----------
    eps : float
        Restitution in (0, 1].

    Returns
    -------
    float
        The unique r = beta/w0 >= 0 with restitution(r) = eps.

    Examples
    --------
    >>> from twoball.model import decay_ratio
    >>> decay_ratio(1.0), round(decay_ratio(0.5), 6)
    (0.0, 0.255276)
    """
    if not 0.0 < eps <= 1.0:
        raise ParameterError(f"a restitution must be a number in (0, 1]; got {eps!r}")
    return _decay_ratio(eps)


@njit
def _decay_ratio(eps: float) -> float:
    if eps == 1.0:
        return 0.0
    target = -math.log(eps)
    low, high = 0.0, 1.0
    while _log_restitution(high) < target:
        low, high = high, 2.0 * high
    while True:
        mid = 0.5 * (low + high)
        if mid == low or mid == high:  # noqa: SIM109 (numba)
            break
        if _log_restitution(mid) < target:
            low = mid
        else:
            high = mid
    # pick the closer of the two neighbouring floats
    low_error = abs(_log_restitution(low) - target)
    return low if low_error <= abs(_log_restitution(high) - target) else high


def damping_ratios(eps01: float, eps12: float, mu: float) -> tuple[float, float]:
    """zeta01 and zeta12 from the two restitutions (docs/model.md, "Restitution and damping").

    Floor: w0 = 1, so zeta01 = r(eps01). Ball pair: w0^2 = (1 + mu)/mu and beta = zeta12 w0^2,
    so zeta12 = r(eps12) sqrt(mu/(1 + mu)).
    """
    return decay_ratio(eps01), decay_ratio(eps12) * math.sqrt(mu / (1.0 + mu))


def floor_contact_time(r: float) -> float:
    """Duration tau_f of one floor contact (docs/model.md, "Restitution and damping").

    Parameters
    ----------
    r : float
        Decay ratio zeta01 >= 0 of the floor contact.

    Returns
    -------
    float
        tau_f in units of the lower ball's time scale: pi for an elastic floor, 2 at critical
        damping.

    Examples
    --------
    >>> import math
    >>> from twoball.model import floor_contact_time
    >>> floor_contact_time(0.0) == math.pi, floor_contact_time(1.0)
    (True, 2.0)
    """
    if r < 1.0:
        return math.acos(2.0 * r * r - 1.0) / math.sqrt(1.0 - r * r)
    if r == 1.0:
        return 2.0
    return math.acosh(2.0 * r * r - 1.0) / math.sqrt(r * r - 1.0)


def initial_gap_height(height: float, tau_d: float) -> float:
    """X2(0) = (sqrt(H) + tau_d/sqrt(2))^2 (docs/model.md, "Initial condition")."""
    root = math.sqrt(height) + tau_d / math.sqrt(2.0)
    return root * root  # inf, not OverflowError, for an absurd gap: the domain check refuses it


def icm_meeting(height, gap, eps01):
    """Where the balls first meet in the independent contact model (docs/model.md, "What is
    measured"): the lower ball dropped from H bouncing on the floor with eps01, the upper one
    released dH higher, both from rest (g = 1). Returns the time, the height and the lower
    ball's velocity then (numbers, or arrays of the inputs' broadcast shape).

    The textbook case meets on the lower ball's first flight. A larger gap (dH above about
    4 eps01 (1 + eps01) H) meets on a later flight, or on the lower ball at rest once its
    bounces have died out (eps01 < 1): the first flight's formula gave a collision below the
    floor there, and a negative h_ICM (-3.7e6 at tau_ratio 1000, a researcher's trial). Flight
    k starts at T_k = v_i (1 + 2 eps01 (1 - eps01^k) / (1 - eps01)) at speed eps01^(k+1) v_i; the
    upper ball, falling alike, closes in at a constant speed, and flight k holds the meeting
    when the upper ball would reach the floor by its end (found in closed form, not by
    stepping through flights)."""
    v_i = np.sqrt(2.0 * np.asarray(height, dtype=float))
    gap, eps01 = np.asarray(gap, dtype=float), np.asarray(eps01, dtype=float)
    landing = np.sqrt(2.0 * (v_i * v_i / 2.0 + gap))  # the upper ball at the floor, alone
    elastic = eps01 >= 1.0
    ratio = np.where(elastic, 0.5, eps01)  # (a stand-in where elastic, not used there)
    # flights needed: T_(k+1) >= landing
    with np.errstate(divide="ignore", invalid="ignore"):
        left = 1.0 - (landing / v_i - 1.0) * (1.0 - ratio) / (2.0 * ratio)
        damped = np.log(np.maximum(left, 1e-300)) / np.log(ratio) - 1.0
    flights = np.where(elastic, (landing / v_i - 1.0) / 2.0 - 1.0, damped)
    k = np.maximum(np.ceil(flights - 1e-9), 0.0)  # (rounding: checked below)
    at_rest = ~elastic & (left <= 0.0)  # the bounces die out before the upper ball arrives

    def flight(k):
        """Flight k's start, its take-off speed and the time into it at which they meet."""
        bounced = np.where(elastic, 2.0 * k, 2.0 * ratio * (1.0 - ratio**k) / (1.0 - ratio))
        start, up = v_i * (1.0 + bounced), v_i * eps01 ** (k + 1.0)
        return start, up, (v_i * v_i / 2.0 + gap - start * start / 2.0) / (up + start)

    k = np.where(at_rest, 0.0, k)
    # (where the lower ball is at rest the flight's values are not taken, and may overflow:
    # H = 1e-320 printed a RuntimeWarning from the command line, a researcher's trial)
    with np.errstate(over="ignore", invalid="ignore"):
        start, up, closing = flight(k)
        # (k rounded one flight off: the meeting then lies past the flight's end, take the
        # next, or before its start, take the one before)
        late = closing > 2.0 * up * (1 + 1e-12)
        early = (closing < -1e-12 * v_i) & (k > 0)
        k = np.where(at_rest, k, k + np.where(late, 1.0, 0.0) - np.where(early, 1.0, 0.0))
        start, up, closing = flight(k)
        time = np.where(at_rest, landing, start + closing)
        level = np.where(at_rest, 0.0, up * closing - closing * closing / 2.0)
        speed = np.where(at_rest, 0.0, up - closing)
    if time.ndim == 0:
        return float(time), float(level), float(speed)
    return time, level, speed


def icm_height(height: float, gap: float, eps01: float, eps12: float, mu: float) -> float:
    """Apex of the upper ball in the independent contact model, the textbook prediction
    (docs/model.md, "What is measured"; paper section II).

    The steps of the paper with eps01 at the floor and eps12 between the balls: the lower ball
    reaches the floor at v_i = sqrt(2H) and leaves at eps01 v_i; the balls meet at
    t_c = dH/(v_i (1 + eps01)) (:func:`icm_meeting`: a later flight for a larger gap); the upper
    ball leaves that collision at v2' and rises to z_c + v2'^2/2. With eps01 = eps12 = eps and
    a meeting on the first flight this is exactly
    (H (eps^2 + 2 eps - mu)^2 + dH (1 + mu)(mu - eps)) / (1 + mu)^2.

    Parameters
    ----------
    height : float
        Drop height H of the lower ball.
    gap : float
        dH = X2(0) - H, how much higher the upper ball starts.
    eps01, eps12 : float
        Restitution at the floor and between the balls.
    mu : float
        Mass ratio m2/m1.

    Returns
    -------
    float
        The apex height of the upper ball.

    Examples
    --------
    Elastic balls and a very light upper ball: nine times the drop height.

    >>> from twoball.model import icm_height
    >>> round(icm_height(1.0, 0.0, 1.0, 1.0, 1e-12), 9)
    9.0
    """
    time, z_c, v1 = icm_meeting(height, gap, eps01)
    v2_after = upper_after_collision(v1, -time, eps12, mu)
    return z_c + 0.5 * v2_after * v2_after


def upper_after_collision(lower: float, upper: float, eps: float, mu: float) -> float:
    """The upper ball's velocity after an instantaneous collision (docs/model.md, "What is
    measured"): momentum kept, and the relative velocity reversed times eps; mu = m_upper /
    m_lower, velocities before the collision (numbers or arrays)."""
    return (mu * upper + lower + eps * (lower - upper)) / (1.0 + mu)
