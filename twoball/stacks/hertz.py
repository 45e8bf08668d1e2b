"""Stacks of N balls with the Hertz force and Hunt-Crossley damping (docs/model.md, "Stacks of
N balls"; docs/stacks.md).

**Model.** A contact compressed by delta = -eta > 0 pushes with

    f = delta^(3/2) (1 + lam delta')      while delta > 0 and 1 + lam delta' > 0, else 0,

Hertz's elastic law with the damping of Hunt and Crossley (1975), which vanishes with the
compression, so the force is continuous at first touch (the linear dashpot's is not). It never
pulls: when a contact separates faster than 1/lam the force is cut at zero (the clamp), as the
linear model's is.

**Units.** With a Hertz stiffness k_h (f = k_h delta^(3/2)), lengths are in
L = (m_0 g / k_h)^(2/3), the static compression of ball 0 under its own weight, and times in
sqrt(L / g); so H = h / L, and every contact has unit stiffness, as in the linear model. H enters
only through the impact speed sqrt(2H): a Hertz contact lasts about 3.2 m^(2/5) v^(-1/5).

**Restitution.** For Hunt-Crossley the restitution of an isolated contact depends on lam v only
(scaling delta = A u, t = T s with A = v T, T = m^(2/5) v^(-1/5) removes m and v). So
:func:`damping_factor` finds, once per eps, the Lambda with restitution(Lambda) = eps on the
normalised contact u'' = -u^(3/2) (1 + Lambda u'), u(0) = 0, u'(0) = 1, and each contact gets
lam = Lambda / v at its *calibration speed* v: the closing speed of its collision in the ICM
chain (sqrt(2H) for the floor). A slower contact is bouncier (1 - e ~ lam v), as real balls
are. The floor contact time tau_f, which sets the gaps, is that of the calibrated floor contact.

**Solution.** The default is the compiled path of :mod:`twoball.kernels.hertz` (Taylor series
of the time-changed motion on the contact forces' displacement, accurate to rounding, its
switches found on the series, and these certified steps only where the series cannot show
them). This module's own, ``method="DOP853"``, is kept as a reference. Free flight is exact:
with no contact active,
every ball is a parabola and the next touch, clamp or apex is a root of a polynomial of degree
at most two. A phase with a contact active is integrated with scipy's DOP853 (rtol 1e-12), whose
every step is bounded so that no touch or release (a root of some overlap eta) can be stepped
over: the energy never rises, so it bounds every overlap, speed and force over the whole run
(:func:`_force_bounds`); with the contacts active in a phase, that bounds eta'' towards each
switch by M (:func:`_phase_bounds`: an active contact opens only by its own force, an inactive
one closes only by its neighbours'); a step keeps eta + eta' h - M h^2 / 2 on its side (the
XX
error, ~1e-12 relative, is not part of the proof). The clamp (1 + lam delta' = 0) and the apexes
are located by sign changes at the step's ends and 8 points of its dense output: estimated, not
proven. A root is refined by Brent's method on the dense output.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from scipy.integrate import DOP853
from scipy.optimize import brentq

from twoball.errors import ParameterError, Status
from twoball.kernels import hertz as hertz_kernel
from twoball.kernels.codes import (
    EVENT_APEX,
    EVENT_FAILED,
    EVENT_REST,
    EVENT_STEPS,
    EVENT_SWITCH,
    EVENT_TIME,
)
from twoball.observables import ContactInterval, RunStats
from twoball.stacks.hertz_contact import (  # (floor_contact_time: this module's name too)
    calibration_speeds,
    damping_factor,
    floor_contact_time,  # noqa: F401
)
from twoball.stacks.model import StackResult, StackTrajectory

# The work a run may take: 30 000 steps, 15-40 s. Inside the domain check_stack accepts the
# largest measured runs take about 10 000 (masses 1e4: 9 825; six balls: 6 004; a heavy stack
# at rest: 3 489); a run that cannot end (Hunt-Crossley bounces grow elastic as they slow, so a
# run to a time far beyond the second apex may bounce for ever) then fails in seconds, not the
# minute and a half 100 000 took.
MAX_STEPS = 30_000
RTOL = 1e-12
PROBES = 8  # dense-output points per step where the clamp and the apexes are looked for


class _Stack:
    """The Hertz stack's equations: overlaps, forces, accelerations."""

    def __init__(self, masses: np.ndarray, lam: np.ndarray):
        self.masses = masses
        self.lam = lam
        self.n = len(masses)
        self.rest_level = -math.inf  # the energy below which it is at rest (set by solve)
        # eta = D x: eta_0 = x_0, eta_c = x_c - x_(c-1); ball j feels (D^T f)_j = f_j - f_(j+1)
        self.difference = np.eye(self.n) - np.eye(self.n, k=-1)

    def overlaps(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """eta and eta' of every contact (floor first)."""
        n = self.n
        return self.difference @ y[:n], self.difference @ y[n:]

    def clamps(self, y: np.ndarray) -> np.ndarray:
        """g = -(1 + lam delta') = lam eta' - 1: a compressed contact pushes while g < 0."""
        return self.lam * (self.difference @ y[self.n :]) - 1.0

    def forces(self, y: np.ndarray, active: np.ndarray) -> np.ndarray:
        eta, deta = self.overlaps(y)
        delta = np.maximum(-eta, 0.0)
        return active * delta**1.5 * np.maximum(1.0 - self.lam * deta, 0.0)

    def rhs(self, active: np.ndarray):
        on = active.astype(float)
        n, transposed, masses = self.n, self.difference.T.copy(), self.masses

        def rhs(_t, y):
            acceleration = transposed @ self.forces(y, on) / masses - 1.0
            return np.concatenate([y[n:], acceleration])

        return rhs

    def energy(self, y: np.ndarray) -> float:
        """Kinetic + gravity + the Hertz potential (2/5) delta^(5/2) of every overlap."""
        n = self.n
        eta = self.overlaps(y)[0]
        delta = np.maximum(-eta, 0.0)
        return float(
            0.5 * (self.masses * y[n:] ** 2).sum()
            + (self.masses * y[:n]).sum()
            + 0.4 * (delta**2.5).sum()
        )


def _force_bounds(stack: _Stack, energy: float) -> np.ndarray:
    """F_c >= f_c for the rest of the run, from the energy, which never rises.

    Gravity's energy sum m_j x_j >= -sum_c W_c delta_c (W_c the weight above contact c), and
    (2/5) d^(5/2) - W d >= -(3/5) W^(5/3), so each compression obeys
    (2/5) delta_c^(5/2) - W_c delta_c <= E + sum_(k != c) (3/5) W_k^(5/3), and the kinetic
    energy is at most E + sum_k (3/5) W_k^(5/3), which bounds every speed.
    """
    m = stack.masses
    weights = np.cumsum(m[::-1])[::-1]
    wells = 0.6 * weights ** (5.0 / 3.0)
    kinetic = energy + wells.sum()
    speed = np.sqrt(2.0 * kinetic / m)
    force = np.empty(stack.n)
    for c in range(stack.n):
        room = energy + wells.sum() - wells[c]
        delta = max(weights[c] ** (2.0 / 3.0), 1.0)
        while 0.4 * delta**2.5 - weights[c] * delta <= room:
            delta *= 1.5
        closing = speed[c] + (speed[c - 1] if c >= 1 else 0.0)
        force[c] = delta**1.5 * (1.0 + stack.lam[c] * closing)
    return force


def _phase_bounds(
    stack: _Stack, force: np.ndarray, active: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on eta_c'' while the phase lasts, with each contact's force in [0, F_c] and only
    active contacts pushing. Gravity cancels between two balls, so
    eta_c'' = f_c (1/m_c + 1/m_(c-1)) - f_(c+1)/m_c - f_(c-1)/m_(c-1) and
    eta_0'' = -1 + (f_0 - f_1)/m_0. Returns (|eta''| <= M, the bound towards the switch): an
    active contact opens only by its own force, eta_c'' <= F_c (1/m_c + 1/m_(c-1)); an inactive
    one closes only by its neighbours', -eta_c'' <= F_(c+1)/m_c + F_(c-1)/m_(c-1) (+ 1 for the
    floor). The second is what a step needs; it stays small for a contact that just touches
    while its neighbours push hard (balls released touching, at the floor's impact)."""
    m = stack.masses
    acting = np.where(active, force, 0.0)
    above = np.append(acting[1:], 0.0)
    below = np.concatenate([[0.0], acting[:-1]])
    own = acting / m
    own[1:] += acting[1:] / m[:-1]
    neighbours = above / m
    neighbours[1:] += below[1:] / m[:-1]
    neighbours[0] += 1.0  # gravity pulls ball 0 towards the floor
    both = own + neighbours
    towards = np.where(active, own, neighbours)
    towards[0] = max(own[0] - 1.0, 0.0) if active[0] else neighbours[0]
    return np.maximum(both, 1e-300), np.maximum(towards, 1e-300)


def solve(
    masses: np.ndarray,
    eps: np.ndarray,
    x_start: np.ndarray,
    height: float,
    apexes_wanted: int,
    t_end: float = math.inf,
    t_eval: np.ndarray | None = None,
):
    """Run a Hertz stack from rest; returns (status, end time, apexes (ball, t, h) rows, contact
    (contact, start, end) rows, contacts before the top ball's first apex, samples or None,
    steps as MAX_STEPS counts them)."""
    n = len(masses)
    speeds = calibration_speeds(masses, eps, height)
    lam = np.array([damping_factor(float(e)) for e in eps]) / speeds
    stack = _Stack(masses, lam)
    y = np.concatenate([x_start, np.zeros(n)])
    weights = np.cumsum(masses[::-1])[::-1]
    room = stack.energy(y) + 0.6 * float((weights ** (5.0 / 3.0)).sum())  # above the minimum
    stack.rest_level = hertz_kernel.rest_level(masses, room)
    force_bound = _force_bounds(stack, stack.energy(y))
    active = np.zeros(n, dtype=bool)
    t = 0.0
    apexes: list[tuple[int, float, float]] = []
    contacts: list[tuple[int, float, float]] = []
    opened = np.zeros(n)
    first = np.zeros(n, dtype=int)
    top_apexes = 0
    times = None if t_eval is None else np.sort(np.asarray(t_eval, dtype=float))
    samples = None if times is None else np.full((len(times), 3 * n), np.nan)
    next_sample = 0
    status = Status.PHASE_LIMIT
    steps = 0
    # the contacts switched at this instant: each switches at most once in an instant (at a
    # clamp reached with no rate, two contacts toggled each other forever at one time)
    fresh = np.zeros(n, dtype=bool)
    switched_at = 0.0
    resting = False

    def record(start: float, stop: float, state_at) -> None:
        nonlocal next_sample
        if times is None:
            return
        while next_sample < len(times) and times[next_sample] <= stop:
            if times[next_sample] >= start:
                state = state_at(times[next_sample])
                samples[next_sample] = np.concatenate(
                    [state, stack.forces(state, active_sampled(state))]
                )
            next_sample += 1

    def active_sampled(_state):
        return active

    while steps < MAX_STEPS:
        free = ~active & ~np.append(active[1:], False)
        if not active.any():
            event_t, kind, index = _next_in_flight(stack, y, t_end - t)
            y0, t0 = y.copy(), t

            def flight(when, y0=y0, t0=t0):
                s = when - t0
                return np.concatenate([y0[:n] + s * (y0[n:] - 0.5 * s), y0[n:] - s])

            record(t0, t0 + event_t, flight)
            y = flight(t0 + event_t)
            t = t0 + event_t
            steps += 1
        else:
            kind, index, t, y, steps = _contact_phase(
                stack,
                y,
                t,
                active,
                free,
                force_bound,
                t_end,
                steps,
                record,
                fresh,
                not resting,
            )
            steps += 1  # a phase counts, so that a run always ends
        if kind == EVENT_TIME or (resting and next_sample == len(times)):
            status = Status.REST if resting else Status.DONE
            break
        if kind == EVENT_STEPS:
            break
        if kind == EVENT_FAILED:  # DOP853 could not go on (a step size below its minimum)
            status = Status.FAILED
            break
        if kind == EVENT_SWITCH:
            if not fresh.any() or t != switched_at:
                fresh[:] = False
            fresh[index], switched_at = True, t
        else:
            fresh[:] = False
        if kind == EVENT_APEX:
            y[n + index] = 0.0
            apexes.append((index, t, float(y[index])))
            if index == n - 1:
                top_apexes += 1
                if top_apexes == apexes_wanted:
                    status = Status.DONE
                    break
            continue
        if kind == EVENT_REST:
            status = Status.REST
            if times is None or next_sample == len(times):
                break
            resting = True  # proven: carry on only to fill the samples asked for
            continue
        # a switch: the contact's function fell through zero, so it toggles
        if active[index]:
            contacts.append((index, float(opened[index]), t))
        else:
            opened[index] = t
            if top_apexes == 0:
                first[index] += 1
        active = active.copy()
        active[index] = not active[index]
    for c in range(n):
        if active[c]:
            contacts.append((c, float(opened[c]), t))
    return status, t, apexes, contacts, first, samples, steps


def _next_in_flight(stack: _Stack, y: np.ndarray, horizon: float) -> tuple[float, int, int]:
    """Time to the next touch or apex with every ball in free flight (exact: parabolas)."""
    n = stack.n
    best, kind, index = horizon, EVENT_TIME, -1
    eta, deta = stack.overlaps(y)
    for c in range(n):
        curvature = -0.5 if c == 0 else 0.0  # eta_0 = x_0 falls at 1; the others' relative
        root = hertz_kernel._first_fall(curvature, deta[c], eta[c])  # (shared with it)
        if root < best:
            best, kind, index = root, EVENT_SWITCH, c
    # a floor contact clamped while still compressed (leaving faster than 1/lam) pushes again
    # once ball 0 slows below that: g_0 = lam (v_0 - s) - 1 falls to zero
    if eta[0] < 0.0 and stack.lam[0] > 0.0:
        again = y[n] - 1.0 / stack.lam[0]
        if 0.0 < again < best:
            best, kind, index = again, EVENT_SWITCH, 0
    for ball in range(n):
        if 0.0 < y[n + ball] < best:
            best, kind, index = y[n + ball], EVENT_APEX, ball
    return best, kind, index


def _tolerances(stack: _Stack, y: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """(eta, eta', tol) of every contact, tol the rounding of eta: 16 ulp of the heights plus
    eta' times 16 ulp of the clock."""
    eta, deta = stack.overlaps(y)
    tol = 16e-16 * ((1.0 + np.abs(y[: stack.n]).sum()) + np.abs(deta) * (1.0 + abs(t)))
    return eta, deta, tol


def _step_for(stack: _Stack, y: np.ndarray, t: float, bound: np.ndarray, active) -> float:
    """The largest h with every eta (or -eta, for a contact that pushes) kept above -tol by
    eta + eta' h - M h^2 / 2, tol the rounding of the heights and of the clock: a root is then
    either crossed (and seen at the step's end) or not reached, and a dip below zero and back
    within one step is shallower than tol."""
    eta, deta, tol = _tolerances(stack, y, t)
    step = math.inf
    for c in range(stack.n):
        value, rate = (-eta[c], -deta[c]) if active[c] else (eta[c], deta[c])
        value = max(value, 0.0) + tol[c]
        root = math.sqrt(rate * rate + 2.0 * bound[c] * value)
        h = (rate + root) / bound[c] if rate >= 0.0 else 2.0 * value / (root - rate)
        step = min(step, h)
    return step


def _local_forces(stack: _Stack, y: np.ndarray, active, span: float, force_bound: np.ndarray):
    """Bounds F_c on each force over the next ``span``, by bootstrap: if the forces stay below F,
    |eta''| <= M(F) (:func:`_phase_bounds`), so a compression stays below
    delta + |delta'| s + M s^2 / 2 and its speed below |delta'| + M s, hence each force below F';
    when F' < F no force can be the first to reach F, so F holds. Falls back to the run's bound."""
    eta, deta = stack.overlaps(y)
    delta, speed = np.maximum(-eta, 0.0), np.abs(deta)
    bound = np.minimum(2.0 * delta**1.5 * (1.0 + stack.lam * speed) + 1e-300, force_bound)
    for _ in range(6):
        both = _phase_bounds(stack, bound, active)[0]
        reach = delta + speed * span + 0.5 * both * span * span
        implied = reach**1.5 * (1.0 + stack.lam * (speed + both * span))
        if (implied < bound).all():
            return bound
        bound = np.minimum(np.maximum(bound, 1.5 * implied), force_bound)
        if (bound == force_bound).all():
            break
    return force_bound


def _certified_step(stack: _Stack, y: np.ndarray, t: float, force_bound: np.ndarray, active):
    """A step over which no overlap changes sign unseen (:func:`_step_for`), with the bound
    towards each switch from the run's forces (:func:`_phase_bounds`), then doubled while the
    forces bounded over the step itself (:func:`_local_forces`) still certify it. (Near a first
    touch the forces are tiny, and the run's bound alone would creep with steps of ~1e-9; in a
    stack at rest they are its weights.)"""
    step = _step_for(stack, y, t, _phase_bounds(stack, force_bound, active)[1], active)
    for _ in range(60):
        trial = 2.0 * step
        local = _local_forces(stack, y, active, trial, force_bound)
        if _step_for(stack, y, t, _phase_bounds(stack, local, active)[1], active) < trial:
            break
        step = trial
    return step


def _switching(stack: _Stack, y: np.ndarray, t: float, active) -> tuple:
    """Each contact's switching function S = max(eta, g) (inactive: it pushes once S < 0) or
    -S (active: it stops once -S < 0), its rate, and its rounding: the one rule of
    docs/model.md, "Bodies, coordinates, forces", with g = lam eta' - 1 for Hertz."""
    n = stack.n
    eta, deta, tol = _tolerances(stack, y, t)
    g = stack.clamps(y)
    ddeta = stack.difference @ stack.rhs(active)(t, y)[n:]
    by_overlap = eta >= g
    value = np.where(by_overlap, eta, g)
    rate = np.where(by_overlap, deta, stack.lam * ddeta)
    rounding = np.where(by_overlap, tol, 1e-12)
    sign = np.where(active, -1.0, 1.0)
    return sign * value, sign * rate, rounding


def _contact_phase(
    stack, y, t, active, free, force_bound, t_end, steps, record, fresh, watch_rest=True
):
    """Integrate a phase with a contact active to its first event (see the module); ``fresh``
    marks the contacts switched at its start time: their functions start at zero, and they do
    not switch again before a step is taken.

    Returns (kind, index, t, y, steps): kind an event of :mod:`twoball.kernels.codes`,
    EVENT_FAILED when DOP853 cannot go on (its step fell below the smallest it takes, as beyond
    the domain double precision carries).

    Watched: each contact's switching function (:func:`_switching`), an event when it falls
    below zero, and the velocity of each ball in free flight going up (its apex)."""
    n = stack.n
    scale = 1.0 + np.abs(y).max()
    solver = DOP853(
        stack.rhs(active.copy()), t, y, t_bound=t_end, rtol=RTOL, atol=RTOL * scale,
        first_step=None,
    )  # fmt: skip
    watched_free = free & (y[n:] > 0.0)

    def functions(state):
        eta, _ = stack.overlaps(state)
        switching = np.maximum(eta, stack.clamps(state))
        return np.concatenate([np.where(active, -switching, switching), state[n:]])

    while steps < MAX_STEPS:
        # at a root to rounding and moving through it, or past it: the switch is here
        value, rate, rounding = _switching(stack, solver.y, solver.t, active)
        due = (value < -rounding) | ((value <= rounding) & (rate < 0.0))
        if solver.t == t:
            due &= ~fresh  # they have just switched
        if due.any():
            return EVENT_SWITCH, int(np.flatnonzero(due)[0]), solver.t, solver.y.copy(), steps
        solver.max_step = _certified_step(stack, solver.y, solver.t, force_bound, active)
        t_old = solver.t
        before = functions(solver.y)
        solver.step()
        steps += 1
        if solver.status == "failed":  # reported as the run's status, not an exception
            return EVENT_FAILED, -1, solver.t, solver.y.copy(), steps
        dense = solver.dense_output()
        hit = None
        previous_t, previous = t_old, before
        for when in np.linspace(t_old, solver.t, PROBES + 2)[1:]:
            now = functions(dense(when) if when < solver.t else solver.y)
            falls = (previous >= 0.0) & (now < 0.0)
            falls[n:] &= watched_free & (previous[n:] > 0.0)
            if falls.any():
                roots = []
                for k in np.flatnonzero(falls):

                    def value_at(moment, k=k, dense=dense):
                        return functions(dense(moment))[k]

                    root = brentq(value_at, previous_t, when, xtol=1e-15 * (1 + abs(when)))
                    roots.append((root, int(k)))
                hit = min(roots)
                break
            previous_t, previous = when, now
        record(t_old, hit[0] if hit else solver.t, dense)
        if hit:
            root, k = hit
            state = dense(root)
            if k >= n:
                return EVENT_APEX, k - n, root, state, steps
            return EVENT_SWITCH, k, root, state, steps
        if solver.status == "finished":
            return EVENT_TIME, -1, solver.t, solver.y.copy(), steps
        if watch_rest and _settled(stack, solver.y):
            return EVENT_REST, -1, solver.t, solver.y.copy(), steps
    return EVENT_STEPS, -1, solver.t, solver.y.copy(), steps


def _settled(stack: _Stack, y: np.ndarray) -> bool:
    """True when no contact can open again, which is proven by the energy (docs/model.md, "The
    Hertz force", rest): with W_c the weight above contact c, the potential is a sum over contacts
    of W_c eta_c + (2/5) delta_c^(5/2), least at delta_c = W_c^(2/3), where it is -(3/5) W_c^(5/3);
    contact c open (eta_c >= 0) costs at least (3/5) W_c^(5/3) more. The energy never rises, so
    once it lies below the least of these (the top ball's) above the minimum, less the
    integration's error in it (:func:`twoball.kernels.hertz.rest_level`), no ball flies again.
    """
    return stack.energy(y) < stack.rest_level


def solve_compiled(
    stack, apexes_wanted: int, t_end: float, times: np.ndarray | None, dense: bool
) -> StackResult:
    """The compiled path, :func:`twoball.kernels.hertz.run` (the default, accurate to rounding):
    a :class:`~twoball.stacks.model.StackResult` for a stack checked for the Hertz force
    (``check_stack(..., force="hertz")``: its gaps in units of the Hertz floor contact time,
    :func:`floor_contact_time`); with ``dense`` the state at every step's end kept, for
    :func:`between_nodes`."""
    eps = np.asarray(stack.eps, dtype=float)
    lam = np.array([damping_factor(float(e)) for e in eps])
    lam /= calibration_speeds(stack.masses, eps, stack.height)
    sorted_times = np.empty(0) if times is None else np.sort(np.asarray(times, dtype=float))
    code, end, apex_rows, contact_rows, first, samples, steps, nodes = hertz_kernel.run(
        stack.masses, lam, stack.x_start, apexes_wanted, t_end, sorted_times, dense
    )
    apexes = [(int(b), float(w), float(h)) for b, w, h in apex_rows]
    contacts = [(int(c), float(a), float(b)) for c, a, b in contact_rows]
    run = (Status(code), float(end), apexes, contacts, first, samples, int(steps))
    result = _result(stack, "compiled", times, *run)
    if dense:
        result.dense = partial(between_nodes, nodes, stack.masses)
    return result


def between_nodes(nodes: np.ndarray, masses: np.ndarray, times: np.ndarray) -> StackTrajectory:
    """The states at ``times`` (within the run) from a compiled run's dense output, its
    ``nodes``: the state at the start and at every step's end (rows t, heights, velocities,
    forces), with cubics between them (:func:`twoball.kernels.hertz.between_nodes`). Exact in
    free flight; within a contact the steps are a tenth to a twentieth of it, and the heights
    are within ~1e-5 of the largest compression of the step's own (tests/test_hertz.py)."""
    return StackTrajectory(times, *hertz_kernel.between_nodes(nodes, masses, times))


def solve_dop853(
    stack, apexes_wanted: int, t_end: float, times: np.ndarray | None, dense: bool
) -> StackResult:
    """This module's own integration (:func:`solve`, scipy's DOP853), kept as the reference; as
    :func:`solve_compiled`, without a dense output."""
    if dense:
        raise ParameterError("dense_output is for the compiled methods only; use t_eval")
    eps = np.asarray(stack.eps, dtype=float)
    run = solve(stack.masses, eps, stack.x_start, stack.height, apexes_wanted, t_end, times)
    return _result(stack, "DOP853", times, *run)


# The Hertz methods by name, all of :data:`twoball.stacks.stack.METHODS`' one signature.
METHODS = {"compiled": solve_compiled, "DOP853": solve_dop853}


def _result(
    stack, method: str, times, status, end, apexes, contacts, first, samples, steps
) -> StackResult:
    """A run's rows as a :class:`~twoball.stacks.model.StackResult`; its statistics are the
    run's steps (the integrator's, and one a free-flight phase)."""
    per_ball: list[list[tuple[float, float]]] = [[] for _ in range(stack.balls)]
    for ball, when, where in apexes:
        per_ball[ball].append((when, where))
    trajectory = None
    if times is not None:  # (sampled in increasing order: given back in the order asked)
        n, given = stack.balls, np.asarray(times, dtype=float)
        rows = np.empty_like(samples)
        rows[np.argsort(given, kind="stable")] = samples
        trajectory = StackTrajectory(given, rows[:, :n], rows[:, n : 2 * n], rows[:, 2 * n :])
    return StackResult(
        stack=stack,
        force="hertz",
        method=method,
        apexes=per_ball,
        contacts=[ContactInterval(c, s, e) for c, s, e in sorted(contacts, key=lambda r: r[1])],
        contacts_first=[int(k) for k in first],
        end_time=end,
        status=status,
        trajectory=trajectory,
        stats=RunStats(steps=steps),
    )
