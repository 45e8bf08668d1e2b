"""The compiled Hertz stack (docs/stacks.md, "How each force is solved"; docs/model.md, "The
Hertz force"): the method of :mod:`twoball.stacks.hertz` in numba, with a different integrator.

Free flight is exact (parabolas; touches, clamps and apexes are roots of quadratics). A phase
with a contact active is integrated by Taylor series of order :data:`ORDER` (docs/stacks.md,
"Why a Taylor series of the time-changed motion"):

- **The time change makes the motion analytic.** The force delta^(3/2) is not smooth where a
  contact touches or releases (the overlap is linear in time there). With rho_c = sqrt(delta_c)
  for each active contact and dt = J dtau, J the product of the active rho, the equations are
  polynomial in (t, x, v, rho) (drho_c/dtau = -(J / rho_c) eta_c' / 2, the force rho^3 (1 -
  lam eta')), and their solution is analytic in tau through a touch (rho starts at 0) and a
  release (rho falls through 0). Each step computes the series of every variable by the
  recurrences of products (:func:`_series`) and takes the step at which the last term of each
  is :data:`TOLERANCE` of its scale (Jorba and Zou's rule, the radius of convergence from the
  last few coefficients, :func:`_taylor_step`): truncation error at rounding, in steps 4 to 6
  times longer than the eighth-order Runge-Kutta this replaced.
- **Each step integrates the contact forces' effect only.** From a step's start (x0, v0), every
  height is x0 + v0 s - s^2/2 + w(s), s the clock's series, and the series carried are w, w'
  from zero (w_j'' = (f_j - f_(j+1)) / m_j); a ball in free flight has w = 0 exactly, so its apex
  is exact (s = v0), and the tolerance is against the contact's own scale (the largest
  compression and speed the energy allows), not heights of order H.
- **Nothing is rounded to an ulp of H at every step** (:func:`_advance`): the overlaps eta and
  their rates are carried from step to step, moved by the same w, w' as the heights, never
  rebuilt as differences of heights, and every carried quantity and the clock is a compensated
  sum moved on with exact products.
- **The state at an event is the series' own** at the event's tau (the series is the step's
  dense output, at the step's accuracy): a switch is found on it by regula falsi, an apex or
  a sample time by Newton's method on the clock's series. A run's dense output, when asked
  (``dense``), is coarser: the state at every step's end (:func:`_node`), with cubics between
  (:func:`between_nodes`), to sample a run once its end is known.

No touch or release is stepped over, and most are stepped to in one step, found on the series
(docs/stacks.md, "How each force is solved"): an open contact's overlap is concave in time (its
eta'' is minus its neighbours' forces over their masses, and no force pulls), so if it is open
at both ends of a step it is open throughout, and a touch shows as the overlap's sign at the
step's end; a contact in the series keeps rho > 0 over the step or has rho' < 0 there, bounded
from its coefficients (:func:`_releases_shown`), so its release is the one root of rho in the
step. Past a release the clock runs back: every switching function is looked at again at the
first root found. Where these do not hold (a contact open but still overlapping, after a clamp;
a rho that may dip through zero and back), the certified steps of :mod:`twoball.stacks.hertz`
(the energy, which never rises, bounds every force; with the contacts active in a phase that
bounds eta'' towards each switch; each step keeps eta + eta' h - M h^2 / 2 on its side), ported
as they are (:mod:`twoball.kernels.certified`), cut the step on the clock; a span certified so
holds for every step inside it, so :data:`~twoball.kernels.certified.AHEAD` steps are certified
at once. The clamp (1 + lam delta' = 0) is looked for at
:data:`PROBES` points of each step in which eta', bounded from its series, can reach 1 / lam,
and refined by regula falsi: estimated, not proven (as in :mod:`twoball.stacks.hertz`). A
contact touching with neither compression nor speed (balls released touching) would stall the
time change (rho = rho' = 0, so J = 0): it is left out of one first step short enough that its
force, bounded as in the certified steps, could not move anything by a thousandth of the
tolerance.
"""

from __future__ import annotations

import math

import numpy as np

from twoball.jit import njit
from twoball.kernels.certified import (
    STALL,
    _needs_certifying,
    _power,
    _recertified,
    _weights,
    force_bounds,
)
from twoball.kernels.codes import STATUS_DONE, STATUS_FAILED, STATUS_PHASES, STATUS_REST
from twoball.kernels.runs import _room_for_one
from twoball.kernels.taylor import (
    ORDER,
    TOLERANCE,
    _clamp_reachable,
    _function_root,
    _functions,
    _motion,
    _releases_shown,
    _series,
    _taylor_step,
    _time_root,
    _value,
)

MAX_STEPS = 300_000  # a run that cannot end fails within seconds (a step takes ~4 us)
PROBES = 8  # points per step where the clamp is looked for


# what ends a phase
K_SWITCH, K_APEX, K_TIME, K_REST, K_STEPS, K_FAILED = 0, 1, 2, 3, 4, 5


@njit
def energy(masses, x, v) -> float:
    """Kinetic + gravity + the Hertz potential (2/5) delta^(5/2) of every overlap."""
    total = 0.0
    for j in range(masses.size):
        eta = x[j] - (x[j - 1] if j >= 1 else 0.0)
        delta = max(-eta, 0.0)
        total += 0.5 * masses[j] * v[j] * v[j] + masses[j] * x[j] + 0.4 * delta * _power(delta)
    return total


@njit
def _overlaps(x, v, eta, deta) -> None:
    for c in range(x.size):
        eta[c] = x[c] - (x[c - 1] if c >= 1 else 0.0)
        deta[c] = v[c] - (v[c - 1] if c >= 1 else 0.0)


@njit
def _tick(t, t_low, s):
    """t + t_low moved on by s, a compensated sum (Knuth's two-sum): the clock, or a carried
    quantity, kept to an ulp over thousands of steps rather than losing one at every step."""
    total = t + s
    moved = total - t
    t_low += (t - (total - moved)) + (s - moved)
    high = total + t_low
    return high, t_low - (high - total)


@njit
def _product(a, b):
    """a b as p + e exactly (Dekker's two-product)."""
    p = a * b
    a_high = a * 134217729.0
    a_high -= a_high - a
    b_high = b * 134217729.0
    b_high -= b_high - b
    a_low, b_low = a - a_high, b - b_high
    return p, ((a_high * b_high - p) + a_high * b_low + a_low * b_high) + a_low * b_low


@njit
def settled(masses, x, v, level) -> bool:
    """True when no contact can open again, proven by the energy (twoball.stacks.hertz._settled):
    below ``level`` (:func:`rest_level`)."""
    return energy(masses, x, v) < level


# What the rest test allows for the integration's error in the energy, a fraction of the energy
# at release above the least potential: measured up to 3e-12 (compiled) and 3e-7 (DOP853) of
# the energy at release (tests/test_hertz.py, the elastic stacks).
REST_SLACK = 1e-5


@njit
def rest_level(masses, room) -> float:
    """The energy below which the stack is at rest (docs/model.md, "The Hertz force", rest): the
    least potential, -(3/5) sum W_c^(5/3), plus the margin the top ball's contact needs to open,
    (3/5) W_top^(5/3), less the integration's error, :data:`REST_SLACK` of ``room`` (the energy
    at release above the least potential), or half the margin where that is less (a light top
    ball's margin is below that error: as before, not proven beyond it, docs/stacks.md, Limits).
    """
    weights = _weights(masses)
    least = -0.6 * (weights ** (5.0 / 3.0)).sum()
    margin = 0.6 * weights[-1] ** (5.0 / 3.0)
    return least + margin - min(0.5 * margin, REST_SLACK * room)


@njit
def _first_fall(a, b, c) -> float:
    """The first s >= 0 at which a s^2 + b s + c (a <= 0) falls through zero, 0 if it is not
    positive and falling now, inf if never: where an inactive overlap closes."""
    if c <= 0.0 and (b < 0.0 or (b == 0.0 and a < 0.0)):
        return 0.0
    if a == 0.0:
        return -c / b if b < 0.0 else math.inf
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return math.inf
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    larger = q / a
    if q != 0.0:
        larger = max(larger, c / q)
    return larger if larger > 0.0 else math.inf


@njit
def _next_in_flight(lam, eta, deta, v, horizon):
    """(time, kind, index) of the next touch, re-push or apex with every ball in free flight:
    roots of quadratics (exact)."""
    n = v.size
    best, kind, index = horizon, K_TIME, -1
    for c in range(n):
        root = _first_fall(-0.5 if c == 0 else 0.0, deta[c], eta[c])
        if root < best:
            best, kind, index = root, K_SWITCH, c
    # a floor contact clamped while still compressed pushes again once ball 0 slows below 1/lam
    if eta[0] < 0.0 and lam[0] > 0.0:
        again = v[0] - 1.0 / lam[0]
        if 0.0 < again < best:
            best, kind, index = again, K_SWITCH, 0
    for ball in range(n):
        if 0.0 < v[ball] < best:
            best, kind, index = v[ball], K_APEX, ball
    return best, kind, index


@njit
def _advance(s, z, state, low, full) -> None:
    """Move the carried state (rows x, v, eta, eta', each as state + low, :func:`_tick`; ``full``
    their rounded sums) on by s from a step's start, w, w' = z there, each by its change, products
    exact: eta never rebuilt from heights of order H, nothing losing an ulp of itself per step
    (over thousands of steps, heights of 1e6 had drifted from their overlaps by 1e-8)."""
    n = state.shape[1]
    half, half_low = _product(0.5 * s, s)
    for j in range(n):
        # x_j += v_j s - s^2/2 + w_j
        moved, moved_low = _product(state[1, j] + low[1, j], s)
        high, part = _tick(state[0, j], low[0, j] + moved_low - half_low, moved)
        high, part = _tick(high, part, -half)
        state[0, j], low[0, j] = _tick(high, part, z[j])
        # v_j += w_j' - s
        high, part = _tick(state[1, j], low[1, j], -s)
        state[1, j], low[1, j] = _tick(high, part, z[n + j])
        # eta_c += eta_c' s + w_c - w_(c-1), minus s^2/2 for the floor
        moved, moved_low = _product(state[3, j] + low[3, j], s)
        high, part = _tick(state[2, j], low[2, j] + moved_low, moved)
        if j == 0:
            high, part = _tick(high, part - half_low, -half)
        state[2, j], low[2, j] = _tick(high, part, z[j] - (z[j - 1] if j >= 1 else 0.0))
        # eta_c' += w_c' - w_(c-1)', minus s for the floor
        high, part = state[3, j], low[3, j]
        if j == 0:
            high, part = _tick(high, part, -s)
        state[3, j], low[3, j] = _tick(high, part, z[n + j] - (z[n + j - 1] if j >= 1 else 0.0))
        for row in range(4):
            full[row, j] = state[row, j] + low[row, j]


@njit
def _accelerations(masses, lam, overlaps, rates, active, forces, accel) -> None:
    """Each ball's acceleration (into ``accel``) from the active contacts' forces."""
    n = masses.size
    for c in range(n):
        forces[c] = 0.0
        if active[c] and overlaps[c] < 0.0:
            forces[c] = _power(-overlaps[c]) * max(1.0 - lam[c] * rates[c], 0.0)
    for j in range(n):
        accel[j] = -1.0 + (forces[j] - (forces[j + 1] if j + 1 < n else 0.0)) / masses[j]


@njit
def _due(masses, lam, x, overlaps, rates, t, active, fresh, at_start, accel, forces) -> int:
    """The first contact whose switch is here (at its root to rounding and moving through it,
    or past it), -1 if none (twoball.stacks.hertz._switching)."""
    n = masses.size
    heights = 1.0
    for j in range(n):
        heights += abs(x[j])
    accelerated = False  # the accelerations, needed only at a clamp reached to rounding
    for c in range(n):
        if at_start and fresh[c]:
            continue  # it has just switched
        eta, deta = overlaps[c], rates[c]
        g = lam[c] * deta - 1.0
        if eta >= g:
            value, rate = eta, deta
            rounding = 16e-16 * (heights + abs(deta) * (1.0 + abs(t)))
        else:
            value, rate, rounding = g, 0.0, 1e-12
            if abs(value) <= rounding:
                if not accelerated:
                    _accelerations(masses, lam, overlaps, rates, active, forces, accel)
                    accelerated = True
                rate = lam[c] * (accel[c] - (accel[c - 1] if c >= 1 else 0.0))
        if active[c]:
            value, rate = -value, -rate
        if value < -rounding or (value <= rounding and rate < 0.0):
            return c
    return -1


@njit
def _record(times, samples, next_sample, start, stop, x, v, lam, active) -> int:
    """Fill the samples at times in [start, stop] from the state at ``start`` in free flight
    (``x``, ``v``); returns the next sample's index."""
    n = x.size
    while next_sample < times.size and times[next_sample] <= stop:
        if times[next_sample] >= start:
            s = times[next_sample] - start
            for j in range(n):
                samples[next_sample, j] = x[j] + v[j] * s - 0.5 * s * s
                samples[next_sample, n + j] = v[j] - s
            _sample_forces(samples[next_sample], lam, active)
        next_sample += 1
    return next_sample


@njit
def _sample_forces(row, lam, active) -> None:
    """The contact forces of a sampled state (heights, velocities first in ``row``)."""
    n = lam.size
    for c in range(n):
        row[2 * n + c] = 0.0
        if active[c]:
            eta = row[c] - (row[c - 1] if c >= 1 else 0.0)
            deta = row[n + c] - (row[n + c - 1] if c >= 1 else 0.0)
            if eta < 0.0:
                row[2 * n + c] = _power(-eta) * max(1.0 - lam[c] * deta, 0.0)


@njit(borrow=True)
def _node(nodes, row, t, full, lam, active) -> None:
    """Row ``row`` of ``nodes``, the dense output (docs/stacks.md, "How each force is solved"):
    the state at t, time, heights, velocities and forces (from the carried overlaps
    ``full[2:]``). Element by element, and the array borrowed: slices and reference counts cost
    more than the copy."""
    n = lam.size
    nodes[row, 0] = t
    for j in range(n):
        nodes[row, 1 + j], nodes[row, 1 + n + j] = full[0, j], full[1, j]
        force = 0.0
        if active[j] and full[2, j] < 0.0:
            force = _power(-full[2, j]) * max(1.0 - lam[j] * full[3, j], 0.0)
        nodes[row, 1 + 2 * n + j] = force


@njit
def between_nodes(nodes, masses, times):
    """Heights, velocities and forces (len(times), N) at ``times`` from the dense output
    ``nodes`` (:func:`_node`): between two nodes each height is the cubic with their heights
    and velocities, each velocity the cubic with their velocities and accelerations, each force
    the straight line (docs/stacks.md, "How each force is solved"). Exact in free flight (a
    parabola is such a cubic)."""
    n, last = masses.size, nodes.shape[0] - 1
    x, v, f = np.empty((times.size, n)), np.empty((times.size, n)), np.empty((times.size, n))
    starts = np.searchsorted(nodes[:, 0], times, side="right") - 1
    for k in range(times.size):
        i = min(max(starts[k], 0), max(last - 1, 0))
        j = min(i + 1, last)
        h = nodes[j, 0] - nodes[i, 0]
        s = (times[k] - nodes[i, 0]) / h if h > 0.0 else 0.0
        # the cubic Hermite basis: the values at the two ends, then the slopes
        start, end = (1.0 + 2.0 * s) * (1.0 - s) ** 2, s * s * (3.0 - 2.0 * s)
        rising, falling = s * (1.0 - s) ** 2 * h, s * s * (s - 1.0) * h
        for b in range(n):
            a_i = nodes[i, 1 + 2 * n + b] - (nodes[i, 2 + 2 * n + b] if b + 1 < n else 0.0)
            a_j = nodes[j, 1 + 2 * n + b] - (nodes[j, 2 + 2 * n + b] if b + 1 < n else 0.0)
            a_i, a_j = a_i / masses[b] - 1.0, a_j / masses[b] - 1.0
            x[k, b] = start * nodes[i, 1 + b] + rising * nodes[i, 1 + n + b]
            x[k, b] += end * nodes[j, 1 + b] + falling * nodes[j, 1 + n + b]
            v[k, b] = start * nodes[i, 1 + n + b] + rising * a_i
            v[k, b] += end * nodes[j, 1 + n + b] + falling * a_j
            f[k, b] = (1.0 - s) * nodes[i, 1 + 2 * n + b] + s * nodes[j, 1 + 2 * n + b]
    return x, v, f


@njit
def _state_at(s, x0, v0, z, x, v) -> None:
    """Heights and velocities s after the step's start, from its w, w' = z."""
    n = x0.size
    for j in range(n):
        x[j] = x0[j] + v0[j] * s - 0.5 * s * s + z[j]
        v[j] = v0[j] - s + z[n + j]


@njit
def _left_out_span(lam, eta, deta, c, both, span, limit) -> float:
    """The longest s <= span over which contact c, from delta = max(-eta, 0) and rate deta with
    |eta''| <= both, gives an impulse below ``limit``: a span it can be left out of the series."""
    s = span
    for _ in range(200):
        reach = max(-eta, 0.0) + abs(deta) * s + 0.5 * both * s * s
        if s * _power(reach) * (1.0 + lam[c] * (abs(deta) + both * s)) <= limit:
            return s
        s *= 0.5
    return 0.0


@njit
def contact_phase(
    masses, lam, state, low, full, t, t_low, active, force_bound, t_end, steps, fresh, watch_rest,
    times, samples, next_sample, scales, h_abs, level, nodes, n_nodes,
):  # fmt: skip
    """Integrate a phase with a contact active to its first event by Taylor series (see the
    module), moving the carried state + low (and ``full``, their sum) on in place
    (:func:`_advance`), the clock as t + t_low (:func:`_tick`). ``scales``: each series' scale
    (the rows of :func:`_series`); ``h_abs``: the span on the clock of the last step (what is
    certified ahead); ``nodes``: the dense output so far, its first ``n_nodes`` rows (:func:`_node`;
    empty: none kept).

    Returns (kind, index, t, t_low, steps, next_sample, h_abs, nodes, n_nodes): kind K_FAILED
    when a step falls below the spacing of the clock (beyond the domain double precision
    carries)."""
    n = masses.size
    rows_count = 1 + 3 * n
    S = np.zeros((rows_count, ORDER + 1))
    work_series = np.zeros((9, n, ORDER + 1))
    D, Q, Cb, L, F = work_series[0], work_series[1], work_series[2], work_series[3], work_series[4]
    G, Jo, Pre, Suf = work_series[5], work_series[6], work_series[7], work_series[8]
    J = np.zeros(ORDER + 1)
    W, U, R = 1, 1 + n, 1 + 2 * n
    accel, forces = np.empty(n), np.empty(n)
    before, after, now = np.empty(n), np.empty(n), np.empty(n)
    z = np.empty(2 * n)
    eta0, deta0 = np.empty(n), np.empty(n)
    work = np.empty((3, n))
    x, v, eta, deta = full[0], full[1], full[2], full[3]
    x_old, v_old = np.empty(n), np.empty(n)
    moving = np.zeros(n, dtype=np.bool_)
    watched = np.zeros(n, dtype=np.bool_)
    for j in range(n):
        moving[j] = active[j] or (j + 1 < n and active[j + 1])
    for j in range(n):
        watched[j] = not moving[j] and v[j] > 0.0
    on = np.empty(n, dtype=np.int64)
    used = np.zeros(n, dtype=np.bool_)  # the active contacts in this step's series
    rows = np.empty(rows_count, dtype=np.int64)
    at_start = True
    certified = -math.inf  # no overlap reaches its root unseen before this time
    bounds = np.empty(n)  # |eta''| <= bounds until then
    while steps < MAX_STEPS:
        c = _due(masses, lam, x, eta, deta, t, active, fresh, at_start, accel, forces)
        if c >= 0:
            return K_SWITCH, c, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
        at_start = False
        # the certified span only where a step's series cannot show the switch (see the
        # module): an open contact still overlapping (clamped), or one that would stall
        max_step = t_end - t
        if _needs_certifying(eta, deta, active, scales[R : R + n], scales[U : U + n]):
            certified = _recertified(masses, lam, x, eta, deta, t, force_bound, active,
                                            certified, h_abs, work, bounds)  # fmt: skip
            max_step = min(certified - t, max_step)
        eta0[:], deta0[:] = eta, deta
        # the series and their values now; a contact touching with neither compression nor
        # speed (balls released touching) would stall the time change (rho = rho' = 0): it is
        # left out of a first step short enough that its force could not move anything, one the
        # clock can take: a shorter one (the stall test is against the run's scales, and the
        # force bounded by the run's energy, so at H of 1e8 to 1e10 a contact closing at 6e-3
        # was left out of steps of 1e-12, below the clock's spacing) and it is in the series,
        # its rho or rho' not zero, so J grows from zero and the clock moves
        spacing = 10.0 * (np.nextafter(t, np.inf) - t)
        count, used_rows = 0, 1
        rows[0] = 0
        for c in range(n):
            used[c] = False
            if not active[c]:
                continue
            rho = math.sqrt(max(-eta[c], 0.0))
            if rho <= STALL * scales[R + c] and deta[c] >= -STALL * scales[U + c]:
                mass = min(masses[c], masses[c - 1]) if c >= 1 else masses[c]
                limit = 1e-3 * TOLERANCE * scales[U + c] * mass
                left = _left_out_span(lam, eta[c], deta[c], c, bounds[c], max_step, limit)
                if left > spacing:
                    max_step = min(max_step, left)
                    continue
            used[c] = True
            on[count] = c
            count += 1
            S[R + c, 0] = rho
            rows[used_rows] = R + c
            used_rows += 1
        for j in range(n):
            if moving[j]:
                S[W + j, 0], S[U + j, 0] = 0.0, 0.0
                rows[used_rows], rows[used_rows + 1] = W + j, U + j
                used_rows += 2
        if count > 0:
            S[0, 0] = 0.0
            _series(
                masses, lam, used, moving, on, count, deta0, scales, S, D, Q, Cb, L, F, G, J, Jo,
                Pre, Suf,
            )  # fmt: skip
            tau = _taylor_step(S, scales, rows[:used_rows])
        else:
            # every active contact left out: free flight, tau = t
            S[:, :] = 0.0
            S[0, 1] = 1.0
            tau = max_step
        if tau == math.inf:  # polynomial series (no force): as far as the clock may go
            tau = 1.0
            for _ in range(200):
                if not _value(S, 0, tau) < max_step:
                    break
                tau *= 2.0
        # a release shown by the step's series (each used rho at most once through zero in it),
        # else the certified span
        if not _releases_shown(S, on, count, R, tau):
            certified = _recertified(masses, lam, x, eta, deta, t, force_bound, active,
                                            certified, h_abs, work, bounds)  # fmt: skip
            max_step = min(certified - t, max_step)
        # the step's span on the clock; past a release (in the step) the clock runs back
        natural = _value(S, 0, tau)
        if not natural <= max_step and max_step < spacing:
            if max_step == t_end - t:  # the end, closer than a step can go
                return K_TIME, -1, t_end, 0.0, steps, next_sample, h_abs, nodes, n_nodes
            return K_FAILED, -1, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
        steps += 1
        # the events in the step: each switching function at its end (and, where a clamp can
        # be reached, at probes); each watched ball's apex, exact (its parabola)
        _functions(lam, used, moving, S, 0.0, eta0, deta0, z, before)
        _functions(lam, used, moving, S, tau, eta0, deta0, z, after)
        for c in range(n):
            if active[c] and not used[c]:
                before[c], after[c] = 1.0, 1.0  # left out for this step
        damped = _clamp_reachable(lam, used, active, eta0, D, tau)
        root, kind, index = tau, K_TIME, -1
        probes = PROBES + 1 if damped else 1
        low_tau = 0.0
        for probe in range(1, probes + 1):
            probe_tau = tau * probe / probes
            if probe == probes:
                now[:] = after
            else:
                _functions(lam, used, moving, S, probe_tau, eta0, deta0, z, now)
                for c in range(n):
                    if active[c] and not used[c]:
                        now[c] = 1.0
            found = False
            for c in range(n):
                if before[c] >= 0.0 and now[c] < 0.0:
                    found = True
                    when = _function_root(lam, used, moving, S, c, low_tau, probe_tau, eta0, deta0)
                    if when < root or kind == K_TIME:
                        root, kind, index = when, K_SWITCH, c
            if found:
                break
            before[:] = now
            low_tau = probe_tau
        # past a release in the step the clock runs back, and an overlap that closed before it
        # may open again by the step's end: every function at the first root found, until none
        # has fallen through zero before it
        for _ in range(n):
            if kind != K_SWITCH:
                break
            _functions(lam, used, moving, S, root, eta0, deta0, z, now)
            earlier = False
            for c in range(n):
                if c != index and before[c] >= 0.0 and now[c] < 0.0 and (used[c] or not active[c]):
                    when = _function_root(lam, used, moving, S, c, low_tau, root, eta0, deta0)
                    if when < root:
                        root, index, earlier = when, c, True
            if not earlier:
                break
        s_root = _value(S, 0, root)
        if not s_root <= max_step:
            # cut at the certified span's end (the clock rises up to the first event)
            root, kind, index = _time_root(S, max_step, root), K_TIME, -1
            s_root = _value(S, 0, root)
        if kind == K_TIME and not s_root > spacing:
            return K_FAILED, -1, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
        for j in range(n):
            if watched[j] and 0.0 < v[j] <= s_root:
                root, kind, index, s_root = _time_root(S, v[j], root), K_APEX, j, v[j]
        t_old = t + t_low
        x_old[:], v_old[:] = x, v
        _motion(S, root, moving, z)
        _advance(s_root, z, state, low, full)
        t, t_low = _tick(t, t_low, s_root)
        if 0.0 < natural < math.inf:
            h_abs = natural
        while next_sample < times.size and times[next_sample] <= t:
            if times[next_sample] >= t_old:
                at = times[next_sample] - t_old
                _motion(S, _time_root(S, at, root), moving, z)
                row = samples[next_sample]
                _state_at(at, x_old, v_old, z, row[:n], row[n : 2 * n])
                _sample_forces(row, lam, active)
            next_sample += 1
        if nodes.shape[0] > 0:  # the dense output, asked for
            if n_nodes == nodes.shape[0]:
                nodes = _room_for_one(nodes, n_nodes)
            _node(nodes, n_nodes, t, full, lam, active)
            n_nodes += 1
        if kind != K_TIME:
            return kind, index, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
        if t >= t_end:
            return K_TIME, -1, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
        if watch_rest and settled(masses, x, v, level):
            return K_REST, -1, t, t_low, steps, next_sample, h_abs, nodes, n_nodes
    return K_STEPS, -1, t, t_low, steps, next_sample, h_abs, nodes, n_nodes


@njit
def run(masses, lam, x_start, apexes_wanted, t_end, times, dense=False):
    """Run a Hertz stack from rest at heights ``x_start`` until the top ball's
    ``apexes_wanted``-th apex, ``t_end`` or a proven rest, sampling at the sorted ``times``
    (empty: none). Returns (status, end time, apexes (ball, t, h) rows, contact (contact, start,
    end) rows, contacts before the top ball's first apex, samples (times, 3N), steps (the
    integrator's, and one a free-flight phase, as the budget MAX_STEPS counts them), the dense
    output: with ``dense``, the state at the start and at the end of every step and flight
    (rows t, heights, velocities, forces), else no rows)."""
    n = masses.size
    state, low = np.zeros((4, n)), np.zeros((4, n))  # x, v, eta, eta', each as state + low
    full, zeros = np.zeros((4, n)), np.zeros(2 * n)  # state + low, rounded; no w in flight
    x, v, eta, deta = state[0], state[1], state[2], state[3]  # views of the larger part
    x[:] = x_start
    _overlaps(x, v, eta, deta)
    full[:] = state
    force_bound = force_bounds(masses, lam, energy(masses, x, v))
    weights = _weights(masses)
    room = energy(masses, x, v) + 0.6 * (weights ** (5.0 / 3.0)).sum()  # above the minimum
    level = rest_level(masses, room)
    # each series' scale (the rows of _series): the largest compression and speeds the energy
    # allows, their ratio for the clock
    compression = (2.5 * room) ** 0.4
    scales = np.empty(1 + 3 * n)
    for j in range(n):
        scales[1 + j] = compression
        scales[1 + n + j] = math.sqrt(2.0 * room / masses[j])
        scales[1 + 2 * n + j] = math.sqrt(compression)
    scales[0] = compression / scales[1 + n : 1 + 2 * n].max()
    active = np.zeros(n, dtype=np.bool_)
    fresh = np.zeros(n, dtype=np.bool_)
    opened = np.zeros(n)
    first = np.zeros(n, dtype=np.int64)
    apexes = np.empty((8, 3))
    contacts = np.empty((8, 3))
    n_apex, n_contacts, top_apexes = 0, 0, 0
    samples = np.full((times.size, 3 * n), np.nan)
    next_sample = 0
    status = STATUS_PHASES
    steps = 0
    t, t_low = 0.0, 0.0  # the clock, t + t_low (_tick)
    switched_at = 0.0
    resting = False
    h_abs = math.inf
    # the dense output, only when asked: the state at the start and at each step's end
    nodes = np.empty((4096 if dense else 0, 1 + 3 * n))
    if dense:
        _node(nodes, 0, t, full, lam, active)
    n_nodes = 1 if dense else 0
    while steps < MAX_STEPS:
        if not active.any():
            tau, kind, index = _next_in_flight(lam, full[2], full[3], full[1], t_end - t)
            t_next, t_low = _tick(t, t_low, tau)
            next_sample = _record(
                times, samples, next_sample, t, t_next, full[0], full[1], lam, active
            )
            _advance(tau, zeros, state, low, full)
            t = t_next
            steps += 1
            if dense:
                if n_nodes == nodes.shape[0]:
                    nodes = _room_for_one(nodes, n_nodes)
                _node(nodes, n_nodes, t, full, lam, active)
                n_nodes += 1
        else:
            kind, index, t, t_low, steps, next_sample, h_abs, nodes, n_nodes = contact_phase(
                masses, lam, state, low, full, t, t_low, active, force_bound, t_end, steps, fresh,
                not resting, times, samples, next_sample, scales, h_abs, level, nodes, n_nodes,
            )  # fmt: skip
            steps += 1  # a phase counts, so that a run always ends
        if kind == K_TIME or (resting and next_sample == times.size):
            status = STATUS_REST if resting else STATUS_DONE
            break
        if kind == K_STEPS:
            break
        if kind == K_FAILED:
            status = STATUS_FAILED
            break
        if kind == K_SWITCH:
            if not fresh.any() or t != switched_at:
                fresh[:] = False
            fresh[index], switched_at = True, t
        else:
            fresh[:] = False
        if kind == K_APEX:
            v[index], low[1, index], full[1, index] = 0.0, 0.0, 0.0
            apexes = _room_for_one(apexes, n_apex)
            apexes[n_apex, 0], apexes[n_apex, 1] = index, t
            apexes[n_apex, 2] = x[index] + low[0, index]
            n_apex += 1
            if index == n - 1:
                top_apexes += 1
                if top_apexes == apexes_wanted:
                    status = STATUS_DONE
                    break
            continue
        if kind == K_REST:
            status = STATUS_REST
            if next_sample == times.size:
                break
            resting = True  # proven: carry on only to fill the samples asked for
            continue
        # a switch: the contact's function fell through zero, so it toggles
        if active[index]:
            contacts = _room_for_one(contacts, n_contacts)
            contacts[n_contacts, 0], contacts[n_contacts, 1] = index, opened[index]
            contacts[n_contacts, 2] = t
            n_contacts += 1
        else:
            opened[index] = t
            if top_apexes == 0:
                first[index] += 1
        active[index] = not active[index]
    for c in range(n):
        if active[c]:
            contacts = _room_for_one(contacts, n_contacts)
            contacts[n_contacts, 0], contacts[n_contacts, 1] = c, opened[c]
            contacts[n_contacts, 2] = t
            n_contacts += 1
    apexes, contacts = apexes[:n_apex].copy(), contacts[:n_contacts].copy()
    return status, t, apexes, contacts, first, samples, steps, nodes[:n_nodes]
