"""Reference integrators: the same equations (docs/model.md, "Bodies, coordinates, forces") through
scipy, for comparison only.

These exist to be compared with the exact solver, not to be trusted over it: an adaptive method
with event location can step over a brief contact and silently let the balls pass through each
other (docs/model.md, "Where numerics go wrong").

- ``solve_ivp`` methods (LSODA, Radau, BDF, DOP853, RK45): apexes are located by an event on the
  upper ball's velocity, kept when the ball contact does not push; contacts by events on the
  switching functions, so a contact the step size hides is not seen.
- ``odeint``: LSODA the way the paper used it, on a fixed time grid; apexes are read off the grid
  (a parabola through the highest sample and its neighbours).
"""

from __future__ import annotations

import math

import numpy as np

from twoball.errors import Status
from twoball.model import Drop
from twoball.observables import Outcome, RunStats

IVP_METHODS = ("LSODA", "Radau", "BDF", "DOP853", "RK45")
METHODS = (*IVP_METHODS, "odeint")
DEFAULT_TOL = 1e-8
ODEINT_STEP = 0.01
ODEINT_WINDOW = 50.0


def forces(state: np.ndarray, zeta01: float, zeta12: float) -> tuple[np.ndarray, np.ndarray]:
    """Clamped contact forces f01 and f12 (docs/model.md, "Bodies, coordinates, forces"): active
    when eta < 0 and g < 0."""
    x1, x2, v1, v2 = state
    eta12 = x2 - x1
    g01 = x1 + 2.0 * zeta01 * v1
    g12 = eta12 + 2.0 * zeta12 * (v2 - v1)
    f01 = np.where((x1 < 0) & (g01 < 0), -g01, 0.0)
    f12 = np.where((eta12 < 0) & (g12 < 0), -g12, 0.0)
    return f01, f12


def _right_hand_side(drop: Drop):
    mu, z01, z12 = drop.mu, drop.zeta01, drop.zeta12

    def rhs(t: float, y: np.ndarray) -> list[float]:
        x1, x2, v1, v2 = y
        g01 = x1 + 2.0 * z01 * v1
        f01 = -g01 if (x1 < 0.0 and g01 < 0.0) else 0.0
        eta = x2 - x1
        g12 = eta + 2.0 * z12 * (v2 - v1)
        f12 = -g12 if (eta < 0.0 and g12 < 0.0) else 0.0
        return [v1, v2, -1.0 + f01 - f12, -1.0 + f12 / mu]

    def jacobian(t: float, y: np.ndarray) -> np.ndarray:
        x1, x2, v1, v2 = y
        jac = np.zeros((4, 4))
        jac[0, 2] = jac[1, 3] = 1.0
        if x1 < 0.0 and x1 + 2.0 * z01 * v1 < 0.0:
            jac[2, 0] -= 1.0
            jac[2, 2] -= 2.0 * z01
        eta = x2 - x1
        if eta < 0.0 and eta + 2.0 * z12 * (v2 - v1) < 0.0:
            # f12 = -(x2 - x1) - 2 z12 (v2 - v1); a1 = ... - f12, a2 = ... + f12 / mu
            df12 = np.array([1.0, -1.0, 2.0 * z12, -2.0 * z12])
            jac[2] -= df12
            jac[3] += df12 / mu
        return jac

    return rhs, jacobian


def time_limit(drop: Drop, apexes: int) -> float:
    """A time by which the wanted apexes have surely happened if they happen at all.

    Each flight of the upper ball lasts at most 2 sqrt(2 E) with E its largest possible height
    (all the energy of both balls given to it, (x1 + mu x2)/mu), plus contact time.
    """
    ceiling = (drop.x1_0 + drop.mu * drop.x2_0) / drop.mu
    return math.sqrt(2.0 * drop.x2_0) + (apexes + 1) * (2.0 * math.sqrt(2.0 * ceiling) + 50.0)


def solve(
    drop: Drop,
    apexes: int,
    t_end: float,
    *,
    method: str,
    rtol: float,
    atol: float,
    dense_output: bool = False,
) -> Outcome:
    """Integrate with scipy's ``method``; returns an :class:`~twoball.observables.Outcome` like
    :func:`twoball.exact.solve` (``evaluate`` interpolates the integrator's output)."""
    horizon = min(t_end, time_limit(drop, apexes))
    if method == "odeint":
        return _solve_odeint(drop, apexes, horizon, t_end, rtol, atol, dense_output)
    return _solve_ivp(drop, method, apexes, horizon, t_end, rtol, atol, dense_output)


def _solve_ivp(drop, method, apexes, horizon, t_end, rtol, atol, dense_output):
    from scipy.integrate import solve_ivp  # here: scipy adds 0.4 s to every start of twoball

    rhs, jacobian = _right_hand_side(drop)
    z01, z12 = drop.zeta01, drop.zeta12

    def floor_switch(t, y):
        return max(y[0], y[0] + 2.0 * z01 * y[2])

    # Released touching (tau_ratio = 0), the balls fall with eta exactly 0 until the floor
    # acts: a switching function that is identically zero cannot be bracketed by solve_ivp's
    # event location, so the ball's crossing is taken a hair below zero.
    touching = 1e-12 * (1.0 + drop.x2_0)

    def ball_switch(t, y):
        eta = y[1] - y[0]
        return max(eta, eta + 2.0 * z12 * (y[3] - y[2])) + touching

    def upper_velocity(t, y):
        # zero at v2 = 1e-12 rather than 0, so that the release (v2 = 0, then falling) is not
        # taken for a fall through zero; the apex height moves by (1e-12)^2 / 2
        return y[3] - 1e-12

    upper_velocity.direction = -1.0
    upper_velocity.terminal = True
    implicit = {"jac": jacobian} if method in ("LSODA", "Radau", "BDF") else {}
    t0, y0 = 0.0, np.array([drop.x1_0, drop.x2_0, 0.0, 0.0])
    apex_t, apex_h = [], []
    events = ([], [])
    pieces = []
    failure = None
    calls = steps = 0
    # One solve_ivp call per flight: it stops at a fall of v2 through zero, which is an apex
    # only if the balls do not push then (docs/model.md, "Bodies, coordinates, forces"); otherwise
    # it goes on from there.
    while len(apex_t) < apexes and t0 < horizon:
        try:
            sol = solve_ivp(
                rhs,
                (t0, horizon),
                y0,
                method=method,
                rtol=rtol,
                atol=atol,
                events=(floor_switch, ball_switch, upper_velocity),
                dense_output=dense_output,
                **implicit,
            )
        except (ValueError, ArithmeticError) as error:  # e.g. NaN in a Newton iteration
            failure = f"{method} failed: {error}"
            break
        calls += 1
        steps += sol.t.size - 1
        if dense_output and sol.sol is not None and sol.t.size > 1:
            pieces.append(sol.sol)  # a call that stopped at once has no interpolant
        for contact in (0, 1):
            events[contact].extend(zip(sol.t_events[contact], sol.y_events[contact], strict=True))
        if not sol.success:
            failure = f"{method} failed: {sol.message}"
            break
        if sol.status != 1:  # reached the horizon
            t0 = horizon
            break
        t0, y0 = float(sol.t_events[2][-1]), sol.y_events[2][-1].copy()
        _, f12 = forces(y0, z01, z12)
        if f12 == 0.0:
            apex_t.append(t0)
            apex_h.append(float(y0[1]))
        y0[3] = min(y0[3], 0.0)  # below the event's zero, so it does not fire again at once
    outcome = outcome_from_events(drop, apex_t, apex_h, events, t0, apexes, t_end, horizon, failure)
    outcome = outcome._replace(stats=RunStats(phases=calls, steps=steps))
    if dense_output:
        plot_times = np.linspace(0.0, outcome.end_time, 4001)
        outcome = outcome._replace(evaluate=PiecewiseDense(pieces, z01, z12), plot_times=plot_times)
    return outcome


def outcome_from_events(
    drop: Drop,
    apex_t: list[float],
    apex_h: list[float],
    events: tuple[list, list],
    t0: float,
    apexes: int,
    t_end: float,
    horizon: float,
    failure: str | None,
) -> Outcome:
    """The :class:`~twoball.observables.Outcome` of an event-driven integration: contact
    intervals and counts from the zeros of each contact's switching function (``events[contact]``
    holds (t, state) pairs), the run's end, its status and reason. ``t0`` is where the
    integration stopped; ``failure`` the integrator's complaint, if any."""
    end = apex_t[-1] if len(apex_t) == apexes else t0
    contacts = []
    counts = [0, 0]
    for contact in (0, 1):
        start = None
        for t_event, y_event in events[contact]:
            if t_event > end:
                break
            # the switching function falls through zero when the contact starts to push
            rising = _switch_rate(y_event, contact, drop) > 0.0
            if not rising and start is None:
                start = float(t_event)
                if not apex_t or t_event < apex_t[0]:
                    counts[contact] += 1
            elif rising and start is not None:
                contacts.append((contact, start, float(t_event)))
                start = None
        if start is not None:
            contacts.append((contact, start, end))
    status, reason = (Status.FAILED, failure) if failure else (Status.DONE, None)
    if reason is None and len(apex_t) < apexes and t_end > horizon:
        status = Status.NO_APEX
        reason = f"no apex {len(apex_t) + 1} before t = {horizon:.6g}"
    rows = np.array(contacts, dtype=float).reshape(-1, 3)
    return Outcome(
        apex_t=apex_t,
        apex_h=apex_h,
        contacts=rows,
        end_time=end,
        status=status,
        message=reason,
        contacts_first=counts,
        evaluate=None,
        plot_times=None,
    )


class PiecewiseDense:
    """The state and forces at any times from the interpolants of consecutive solve_ivp calls
    (an object, not a closure, so that a result pickles). Continuous: both sides of a switch
    are the same, ``side`` is accepted for the one signature of dense output."""

    def __init__(self, pieces: list, zeta01: float, zeta12: float) -> None:
        self.pieces, self.zeta01, self.zeta12 = pieces, zeta01, zeta12

    def __call__(self, times: np.ndarray, side: str = "right") -> np.ndarray:
        states = _evaluate_pieces(self.pieces, np.asarray(times, dtype=float))
        f01, f12 = forces(states, self.zeta01, self.zeta12)
        return np.column_stack([states.T, f01, f12])


class GridDense:
    """The odeint grid's rows (x1, x2, v1, v2, f01, f12), linearly interpolated at any times
    (continuous: ``side`` makes no difference)."""

    def __init__(self, grid: np.ndarray, values: np.ndarray) -> None:
        self.grid, self.values = grid, values

    def __call__(self, times: np.ndarray, side: str = "right") -> np.ndarray:
        wanted = np.asarray(times, dtype=float)
        return np.column_stack([np.interp(wanted, self.grid, c) for c in self.values.T])


def _evaluate_pieces(pieces, times: np.ndarray) -> np.ndarray:
    """Dense output of consecutive solve_ivp calls at the given times, shape (4, n); NaN where
    no call reached (after a failure)."""
    states = np.full((4, times.size), np.nan)
    for piece in pieces:
        inside = (times >= piece.t_min) & (times <= piece.t_max)
        if inside.any():
            states[:, inside] = piece(times[inside])
    return states


def _apex_samples(v2: np.ndarray, f12: np.ndarray) -> np.ndarray:
    """Grid indices after which v2 falls through zero while the balls do not push."""
    falling = (v2[:-1] > 0.0) & (v2[1:] <= 0.0) & (f12[:-1] == 0.0) & (f12[1:] == 0.0)
    return np.flatnonzero(falling)


def _switch_rate(y: np.ndarray, contact: int, drop: Drop) -> float:
    """Time derivative of the switching function max(eta, g) at a zero of it."""
    x1, x2, v1, v2 = y
    if contact == 0:
        eta, deta, zeta = x1, v1, drop.zeta01
    else:
        eta, deta, zeta = x2 - x1, v2 - v1, drop.zeta12
    accel = np.array(_right_hand_side(drop)[0](0.0, y))[2:]
    ddeta = accel[0] if contact == 0 else accel[1] - accel[0]
    g = eta + 2.0 * zeta * deta
    return deta if eta >= g else deta + 2.0 * zeta * ddeta


def _solve_odeint(drop, apexes, horizon, t_end, rtol, atol, dense_output):
    """LSODA on a fixed grid of step ODEINT_STEP, observables read off the grid (the paper).

    The grid is integrated in windows of ODEINT_WINDOW and stops after the window in which the
    wanted apex appears, so it does not integrate far past what was asked.
    """
    from scipy.integrate import odeint  # here: scipy adds 0.4 s to every start of twoball

    rhs, jacobian = _right_hand_side(drop)
    per_window = int(round(ODEINT_WINDOW / ODEINT_STEP))
    y0 = np.array([drop.x1_0, drop.x2_0, 0.0, 0.0])
    chunks = [y0[None, :]]
    window = 0
    while window * ODEINT_WINDOW < horizon:
        grid = (window * per_window + np.arange(per_window + 1)) * ODEINT_STEP
        part = odeint(
            rhs,
            chunks[-1][-1],
            grid,
            Dfun=jacobian,
            rtol=rtol,
            atol=atol,
            tfirst=True,
            mxstep=100_000,
        )
        chunks.append(part[1:])
        window += 1
        so_far = np.concatenate(chunks)
        _, f12_so_far = forces(so_far.T, drop.zeta01, drop.zeta12)
        if _apex_samples(so_far[:, 3], f12_so_far).size >= apexes:
            break
    states = np.concatenate(chunks)
    times = np.arange(states.shape[0]) * ODEINT_STEP
    x1, x2, v1, v2 = states.T
    f01, f12 = forces(states.T, drop.zeta01, drop.zeta12)
    # apex: v2 changes sign from + to - between samples while the ball contact is off
    crossing = _apex_samples(v2, f12)
    apex_t, apex_h = [], []
    for i in crossing[:apexes]:
        j = i if x2[i] >= x2[i + 1] else i + 1
        j = min(max(j, 1), len(times) - 2)
        left, mid, right = x2[j - 1], x2[j], x2[j + 1]
        curvature = left - 2.0 * mid + right
        shift = 0.5 * (left - right) / curvature if curvature < 0.0 else 0.0
        apex_t.append(float(times[j] + shift * ODEINT_STEP))
        apex_h.append(
            float(mid - 0.125 * (left - right) * (left - right) / curvature)
            if curvature < 0.0
            else float(mid)
        )
    end = apex_t[-1] if len(apex_t) == apexes else float(times[-1])
    contacts = []
    counts = [0, 0]
    for contact, force in ((0, f01), (1, f12)):
        pushing = force > 0.0
        starts = np.flatnonzero(pushing[1:] & ~pushing[:-1]) + 1
        stops = np.flatnonzero(~pushing[1:] & pushing[:-1]) + 1
        for s in starts:
            later = stops[stops > s]
            stop = times[later[0]] if later.size else end
            if times[s] <= end:
                contacts.append((contact, float(times[s]), float(stop)))
                if not apex_t or times[s] < apex_t[0]:
                    counts[contact] += 1
    status, reason = Status.DONE, None
    if len(apex_t) < apexes and t_end > horizon:
        status = Status.NO_APEX
        reason = f"no apex {len(apex_t) + 1} before t = {horizon:.6g}"
    evaluate = plot_times = None
    if dense_output:
        keep = times <= end
        grid, values = times[keep], np.column_stack([states[keep], f01[keep], f12[keep]])

        evaluate = GridDense(grid, values)
        plot_times = grid
    rows = np.array(contacts, dtype=float).reshape(-1, 3)
    return Outcome(
        apex_t=apex_t,
        apex_h=apex_h,
        contacts=rows,
        end_time=end,
        status=status,
        message=reason,
        contacts_first=counts,
        evaluate=evaluate,
        plot_times=plot_times,
    )
