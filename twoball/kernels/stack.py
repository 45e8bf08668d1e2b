"""The N-ball kernel's phase loop (docs/model.md, "Stacks of N balls"): a phase advanced to its
first event by certified steps over the clusters' closed forms (:mod:`twoball.kernels.clusters`),
a stack run phase by phase, and the exact state at any times from the recorded phases."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from twoball.jit import njit
from twoball.kernels.closed_forms import _release_time
from twoball.kernels.clusters import (
    _bound,
    _check_contact,
    _cluster_id,
    _clusters_ready,
    _ensure_clusters,
    _evaluate_arrays,
    _evaluate_contact,
    _phase,
    _rest_rounding,
    _sizes,
    new_clusters,
)
from twoball.kernels.codes import (
    EVENT_APEX,
    EVENT_REST,
    EVENT_STEPS,
    EVENT_STUCK,
    EVENT_SWITCH,
    EVENT_TIME,
    MAX_PHASES,
    MAX_STEPS_PER_PHASE,
    ROUNDING,
    STATUS_DONE,
    STATUS_PHASES,
    STATUS_REST,
    STATUS_STUCK,
)
from twoball.kernels.phases import (
    BOTH,
    P_NOISE,
    _at_rest,
    _block_states,
    _energy_roots,
    _rest_size,
    prepare,
)
from twoball.kernels.runs import _room_for_one


class Workspace(NamedTuple):
    """:func:`advance_phase`'s arrays, allocated once per run (:func:`new_workspace`): a phase
    of a three-ball drop lasts a few microseconds, of which allocating them took a third."""

    x: np.ndarray  # (N,) heights, velocities, accelerations (see _evaluate_arrays)
    v: np.ndarray
    a: np.ndarray
    shift_x: np.ndarray  # (N,) see _evaluate_arrays
    shift_v: np.ndarray
    shape_z: np.ndarray  # (N, 2N) per phase cluster
    shape_w: np.ndarray
    mode_z: np.ndarray
    mode_w: np.ndarray
    change_z: np.ndarray
    size_change: np.ndarray
    size_value: np.ndarray
    sizes_w: np.ndarray  # (N, N, 2) see _sizes
    sizes_z: np.ndarray  # (1, N, 2)
    solved: np.ndarray  # (N,) bool: contacts whose end is found in closed form
    # the phase's clusters (see clusters._phase)
    lo: np.ndarray  # (N,) int
    hi: np.ndarray
    cid: np.ndarray
    grounded: np.ndarray  # (N,) bool
    modes: np.ndarray  # (N, 2N)
    centre: np.ndarray  # (N, 2)
    size: np.ndarray  # (N,)
    speed: np.ndarray
    of_ball: np.ndarray  # (N,) int
    z: np.ndarray  # (2N,)
    rest_rounding: np.ndarray  # (N,) see clusters._rest_rounding, filled by run
    sized: np.ndarray  # (N,) int, see advance_phase


@njit
def new_workspace(n):
    """A :class:`Workspace` for an n-ball stack."""
    return Workspace(
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2 * n)),
        np.zeros((n, n, 2)),
        np.zeros((1, n, 2)),
        np.zeros(n, dtype=np.bool_),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.bool_),
        np.zeros((n, 2 * n)),
        np.zeros((n, 2)),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n, dtype=np.int64),
        np.zeros(2 * n),
        np.zeros(n),
        np.zeros(n, dtype=np.int64),
    )


@njit(borrow=True)
def advance_phase(
    t,
    e0,
    de0,
    e,
    de,
    active,
    horizon,
    horizon_ball,
    store,
    masses,
    zeta,
    entered_by,
    carried,
    pair,
    work,
):
    """Advance one phase, started at time t from the relative state e0, de0 (the contacts'
    overlaps and their rates: :func:`twoball.kernels.clusters._phase`), to its first event.

    Returns (event, index, tau), the state there written into e, de: a contact switch (index
    the contact), an apex (index the ball; horizon_ball's apex is ``horizon`` away, or -1 for
    the end of the run), the end, rest, a stuck root finder or the step limit. ``pair`` is
    :func:`twoball.kernels.phases.prepare` of a two-ball stack (a placeholder for more balls):
    its rest proof is used for N = 2. ``work`` is a :class:`Workspace`; with every contact
    active and N >= 3 its rest_rounding holds :func:`_rest_rounding` of the phase's start.
    The clusters' closed forms are built (:func:`_ensure_clusters`).

    Compiled without reference counts (it allocates nothing): numba counted each of the ~50
    arrays handed to it, and to the helpers it calls, up and down at every call.
    """
    n = masses.size
    count = _phase(
        active,
        e0,
        de0,
        store,
        masses,
        zeta,
        work.lo,
        work.hi,
        work.cid,
        work.grounded,
        work.modes,
        work.centre,
        work.size,
        work.speed,
        work.of_ball,
        work.z,
    )
    mode_z, sizes_z, solved = work.mode_z, work.sizes_z, work.solved
    solved[:] = False
    kinds, blocks, companions, rates = store.kind, store.blocks, store.companion, store.rates
    contacts, noise, eta_rest, w_rest = store.contacts, store.noise, store.eta_rest, store.w_rest
    cids, grounded, of_ball = work.cid, work.grounded, work.of_ball
    sizes, speeds = work.size, work.speed
    everything = count == 1 and grounded[0] and store.contacts[cids[0]] == n
    rest_rounding = work.rest_rounding
    horizon_contact = -1  # a contact whose force ends at the horizon
    tau = 0.0
    last_step = 0.0
    # Each contact's bounds are formed from its clusters' block sizes, each cluster's once a
    # step (sized: at which step they were formed).
    sized = work.sized
    for c in range(n):
        sized[c] = -1
    steps = 0
    for _ in range(MAX_STEPS_PER_PHASE):
        _evaluate(tau, count, False, work, store, e0, de0, e, de)
        clock = 1.0 + t + tau
        step = horizon - tau
        others = step  # the smallest certified step but that of the contact that limits step
        limit = -1
        event, best = -1, np.inf
        early, early_contact = np.inf, -1
        steps += 1
        for c in range(n):
            if solved[c] and tau > 0.0:
                continue  # its end is the horizon, or beyond it
            value, rate, tol, tol_rate, h, error = _check(
                c, tau, clock, active[c], zeta[c], carried, e, de, work, store, steps
            )
            fresh = c == entered_by and tau == 0.0
            if value <= -tol or (value <= tol and rate < -tol_rate and not fresh):
                shift = 0.0  # one Newton correction, as in twoball.kernels.phases.advance_phase
                if rate < 0.0:
                    shift = min(max(value / -rate, -last_step), h)
                if c == entered_by and tau + shift <= 0.0:
                    shift = 0.0
                if tau + shift < best:
                    best, event = tau + shift, c
            elif active[c] and contacts[cids[of_ball[c]]] == 1 and tau == 0.0:
                # A contact alone in its cluster is a damped oscillator about its static
                # overlap: its force ends at a root found in closed form, which bounds the phase
                # as an apex does (twoball.kernels.phases.advance_phase), not by steps.
                cid_u = cids[of_ball[c]]
                level = tol if fresh and value <= tol else 0.0
                w = -blocks[cid_u, 0, 1, 0]
                release = _release_time(
                    e0[c] - eta_rest[cid_u, 0],
                    de0[c],
                    zeta[c] * w,
                    w,
                    zeta[c],
                    level - eta_rest[cid_u, 0],
                    horizon,
                )
                solved[c] = True
                if release < horizon:
                    horizon, horizon_contact = release, c
                    step = min(step, horizon)
                    others = min(others, horizon)
            else:
                if h < step:
                    others, step, limit = step, h, c
                else:
                    others = min(others, h)
                # Closing on its root: one Newton step s lands within M s^2/2 of it (M the
                # curvature bound), so once that is below the rounding the switch is taken
                # there, if no other contact can switch first, rather than stepped to (its
                # certified step h exceeds s then). tol bounds the rounding generously (16 ulps
                # of every term), so a 512th of it is asked for.
                closing = rate < -tol_rate and not fresh and error <= tol / 512.0
                if closing and tau + value / -rate < early:
                    early, early_contact = tau + value / -rate, c
        if event < 0 and early_contact >= 0 and early <= tau + step:
            event, best = early_contact, early
        if event >= 0:
            _evaluate(best, count, False, work, store, e0, de0, e, de)
            return EVENT_SWITCH, event, best
        if everything:
            margin_ok = True
            cid = cids[0]
            _sizes(kinds, blocks, companions, rates, cid, n, mode_z, 0, sizes_z)
            tol_rest = ROUNDING * noise[cid] * (sizes[0] + speeds[0] * (1.0 + tau) + tau * tau)
            for c in range(n):
                excursion = _bound(w_rest, cid, c, sizes_z, 0, n)
                margin = -eta_rest[cid, c] - excursion
                if n >= 3:  # each contact's own rounding (see _rest_rounding)
                    tol_rest = ROUNDING * (rest_rounding[c] + excursion)
                if not margin > tol_rest:
                    margin_ok = False
            if not margin_ok and n == 2:
                margin_ok = _pair_at_rest(pair, e, de, sizes[0], speeds[0], tau, carried)
            if margin_ok:
                return EVENT_REST, -1, tau
        if tau + step >= horizon:
            _evaluate(horizon, count, False, work, store, e0, de0, e, de)
            if horizon_contact >= 0:
                return EVENT_SWITCH, horizon_contact, horizon
            if horizon_ball >= 0:
                return EVENT_APEX, horizon_ball, horizon
            return EVENT_TIME, -1, horizon
        if not 0.0 < step < np.inf:
            for c in range(n):
                e[c], de[c] = e0[c], de0[c]
            return EVENT_STUCK, -1, tau
        if limit >= 0 and others > 2.0 * step and not everything:
            # Every other contact is certified until tau + others: step the one that limits
            # the step on its own until then, evaluating only the rows it reads
            # (_evaluate_contact; most steps approach the root of the contact that then
            # switches). Its switch, if found before, ends the phase; else the whole stack is
            # looked at again from there.
            reach = tau + others
            at, inner = tau + step, step
            while True:
                _evaluate_contact(
                    at,
                    limit,
                    active[limit],
                    cids,
                    work.lo,
                    grounded,
                    work.modes,
                    of_ball,
                    store,
                    e0,
                    de0,
                    work.a,
                    work.shape_w,
                    work.mode_w,
                    e,
                    de,
                    work.change_z,
                )
                steps += 1
                value, rate, tol, tol_rate, h, error = _check(
                    limit,
                    at,
                    1.0 + t + at,
                    active[limit],
                    zeta[limit],
                    carried,
                    e,
                    de,
                    work,
                    store,
                    steps,
                )
                found = -1.0
                if value <= -tol or (value <= tol and rate < -tol_rate):
                    found = at + (min(max(value / -rate, -inner), h) if rate < 0.0 else 0.0)
                    if limit == entered_by and found <= 0.0:
                        found = at  # as in the loop above: never back to the phase's start
                elif rate < -tol_rate and error <= tol / 512.0:
                    found = at + value / -rate
                if found >= 0.0 and found <= reach:
                    _evaluate(found, count, False, work, store, e0, de0, e, de)
                    return EVENT_SWITCH, limit, found
                if found >= 0.0 or not h > 0.0 or at + h >= reach:
                    break  # looked at again with the others, from here
                at += h
                inner = h
            step = at - tau
        tau += step
        last_step = step
    for c in range(n):
        e[c], de[c] = e0[c], de0[c]
    return EVENT_STEPS, -1, tau


@njit(borrow=True, inline=True)
def _evaluate(tau, count, every_ball, work, store, e0, de0, e, de):
    """:func:`_evaluate_arrays` of the phase's count clusters at tau, from the workspace's and
    the store's arrays."""
    _evaluate_arrays(
        tau,
        count,
        every_ball,
        work.cid,
        work.lo,
        work.hi,
        work.grounded,
        work.centre,
        work.modes,
        store,
        e0,
        de0,
        work.x,
        work.v,
        work.a,
        work.shape_z,
        work.shape_w,
        work.mode_z,
        work.mode_w,
        e,
        de,
        work.change_z,
        work.size_change,
        work.size_value,
        work.shift_x,
        work.shift_v,
    )


@njit(borrow=True, inline=True)
def _check(c, tau, clock, is_active, zeta_c, carried, e, de, work, store, stamp):
    """:func:`_check_contact` of contact c at tau from the evaluated workspace."""
    return _check_contact(
        c,
        tau,
        clock,
        is_active,
        zeta_c,
        carried,
        e,
        de,
        work.a,
        work.shape_w,
        work.of_ball,
        work.cid,
        work.lo,
        work.grounded,
        store,
        work.size,
        work.speed,
        work.mode_w,
        work.sizes_w,
        work.sized,
        stamp,
    )


@njit
def _pair_at_rest(pair, e, de, size, speed, tau, carried):
    """Rest of two balls, both contacts active, proven as :func:`twoball.kernels.runs.run` proves it
    (docs/model.md, "What is measured"): per mode, with the tight bound of a strongly overdamped
    mode (:func:`twoball.kernels.closed_forms._overdamped_bound`). The cluster's total energy, which
    the test above uses, bounds a slow overdamped mode far too loosely (eps = 0.01 under a heavy
    upper ball: rest proven at t = 3310 by twoball.simulate, never by that energy)."""
    params, rest, x_inv, blocks = pair.params, pair.rest, pair.x_inv, pair.blocks
    companions, y_rest, rates, mode_rows = pair.companions, pair.y_rest, pair.rates, pair.mode_rows
    # the two-ball solver's state (x1, eta, v1, eta') is the stack's relative state
    block_states = _block_states(e[0], e[1], de[0], de[1], x_inv, companions, y_rest)
    roots = _energy_roots(BOTH, de[0], de[1], 0.0, 0.0, params, blocks, block_states)
    offset = _rest_size(y_rest)
    tol = ROUNDING * params[P_NOISE] * (size + offset + speed * (1.0 + tau) + tau * tau)
    return _at_rest(roots, params, rest, rates, mode_rows, block_states, tol + carried)


class StackRun(NamedTuple):
    """What :func:`run` returns."""

    status: int
    end_time: float
    apexes: np.ndarray  # (n, 3): ball, t, height, in order
    contacts: np.ndarray  # (n, 3): contact, start, end
    contacts_first: np.ndarray  # (N,) intervals of each contact that start before h1
    phases: np.ndarray  # (n, 2 + 2N): t, active bits, overlaps, their rates (if recorded)
    phase_count: int


@njit
def run(masses, zeta, x_start, apexes_wanted, t_end, record_phases, store):
    """Run a stack from rest at heights ``x_start`` until the top ball's ``apexes_wanted``-th
    apex, ``t_end`` or rest (docs/model.md, "Stacks of N balls"). ``store`` holds the clusters'
    closed forms for these masses and damping ratios (:func:`new_clusters`, or one that earlier
    runs of the same balls filled: :func:`_store_for`).

    The state is carried relative (docs/stacks.md, "How the state is carried"): each contact's
    overlap e[c] = x_c - x_(c-1) (e[0] = x_0, the floor's) and its rate, each phase adding its
    change to them; a height is the sum of the overlaps below it."""
    n = masses.size
    e = np.empty(n)
    e[0] = x_start[0]
    for c in range(1, n):
        e[c] = x_start[c] - x_start[c - 1]
    de = np.zeros(n)
    e_next = np.empty(n)  # where a phase writes its end state
    de_next = np.empty(n)
    work = new_workspace(n)
    # Balls released touching (a gap of zero) start with their contact active and unloaded
    # (force zero either way): left inactive, the compression wave of the first impact reaches
    # it as a tangency of high order (eta ~ -(t - t0)^6 for the fourth contact), which rounding
    # toggles on and off for ever. Active, the contact simply starts to push. Its interval
    # begins where it does: the balls fall together with no force between them, so it first
    # pushes (s < 0: docs/model.md, "Stacks of N balls") when the ball below it is first
    # pushed, as the contact below begins (_begin_unloaded_above). Released before that, it
    # never pushed: no interval, none counted ("What is measured": intervals with f > 0).
    active = np.zeros(n, dtype=np.bool_)
    unloaded = np.zeros(n, dtype=np.bool_)
    opened = np.zeros(n)
    first = np.zeros(n, dtype=np.int64)
    for c in range(1, n):
        if x_start[c] == x_start[c - 1]:
            active[c] = unloaded[c] = True
    t = 0.0
    apexes = np.empty((8, 3))
    n_apex = 0
    heights = np.empty(n)  # at the phase's start, summed from the overlaps
    speeds = np.empty(n)
    apex_passed = np.zeros(n, dtype=np.bool_)  # a lower ball's, since its last contact switch
    top_apexes = 0
    contacts = np.empty((16, 3))
    n_contacts = 0
    phases = np.empty((16 if record_phases else 0, 2 + 2 * n))
    n_phases = 0
    status = STATUS_PHASES
    entered_by = -1
    carried = 0.0
    # the two-ball solver's rest proof, for N = 2 (for more balls a placeholder of the same type)
    pair = prepare(masses[1] if n == 2 else 1.0, zeta[0], zeta[1] if n == 2 else 0.1)
    phase_count = 0
    # the store's arrays read at every phase, taken out once: each read of a named tuple's array
    # counts a reference up and down (atomically)
    ready, eta_rest, noise = store.ready, store.eta_rest, store.noise
    running = True
    while running:
        # Room for one more phase's rows (a phase records at most one phase, one contact
        # interval and n apexes), made here, outside the loop over phases: a table that may be
        # replaced inside a loop has its references counted up and down, atomically, at every
        # pass (a tenth of the eight-ball drop's time when it was the loop over the balls)
        if record_phases:
            phases = _room_for_one(phases, n_phases)
        while n_apex + n > apexes.shape[0]:
            apexes = _room_for_one(apexes, apexes.shape[0])
        contacts = _room_for_one(contacts, n_contacts)
        while True:
            if phase_count == MAX_PHASES:
                running = False
                break
            full = n_apex + n > apexes.shape[0] or n_contacts == contacts.shape[0]
            if full or (record_phases and n_phases == phases.shape[0]):
                break  # made room for above
            phase_count += 1
            if record_phases:
                bits = 0
                for c in range(n):
                    if active[c]:
                        bits += 1 << c
                phases[n_phases, 0], phases[n_phases, 1] = t, bits
                phases[n_phases, 2 : 2 + n] = e
                phases[n_phases, 2 + n :] = de
                n_phases += 1
            height = speed = 0.0
            for ball in range(n):
                height += e[ball]
                speed += de[ball]
                heights[ball], speeds[ball] = height, speed
            # The top ball's apex ends a phase (its height is measured there); a lower ball's is
            # read from its parabola once the phase has passed it, not a phase of its own
            # (docs/performance.md, "What grows with N").
            horizon, horizon_ball = t_end - t, -1
            if not active[n - 1] and 0.0 < speeds[n - 1] < horizon:
                horizon, horizon_ball = speeds[n - 1], n - 1  # a free ball's apex is v away
            if not _clusters_ready(active, ready):
                _ensure_clusters(active, store, masses, zeta)
            if n >= 3 and active.all():
                work.rest_rounding[:] = _rest_rounding(
                    store, _cluster_id(0, n - 1, True, n), heights, speeds, carried
                )
            event, index, tau = advance_phase(
                t,
                e,
                de,
                e_next,
                de_next,
                active,
                horizon,
                horizon_ball,
                store,
                masses,
                zeta,
                entered_by,
                carried,
                pair,
                work,
            )
            for c in range(n):  # the phase's end is the next one's start (copied: swapping the
                e[c], de[c] = e_next[c], de_next[c]  # arrays counted 8 references a phase)
            phase_apexes = n_apex
            for ball in range(n - 1):
                free = not active[ball] and not active[ball + 1]
                rise = speeds[ball]
                if free and not apex_passed[ball] and 0.0 < rise <= tau:
                    apex_passed[ball] = True
                    row = n_apex  # in order of time among this phase's apexes
                    while row > phase_apexes and apexes[row - 1, 1] > t + rise:
                        for column in range(3):  # scalars: a row's view would be counted too
                            apexes[row, column] = apexes[row - 1, column]
                        row -= 1
                    apexes[row, 0], apexes[row, 1] = ball, t + rise
                    apexes[row, 2] = heights[ball] + 0.5 * rise * rise
                    n_apex += 1
            # A state that leaves a grounded cluster of several contacts carries the rounding of
            # its closed form about the static rest (see twoball.kernels.runs.run).
            grounded_top = 0
            while active[0] and grounded_top + 1 < n and active[grounded_top + 1]:
                grounded_top += 1
            if grounded_top > 0:
                cid = _cluster_id(0, grounded_top, True, n)
                offset = 0.0  # summed in a loop: a slice and np.abs allocated and counted
                for c in range(grounded_top + 1):
                    offset += abs(eta_rest[cid, c])
                carried = max(carried, ROUNDING * noise[cid] * offset)
            entered_by = index if event == EVENT_SWITCH else -1
            phase_start = t
            t += tau
            if event == EVENT_SWITCH:
                if unloaded[index]:  # released before it pushed: no interval
                    unloaded[index] = False
                elif active[index]:
                    contacts[n_contacts, 0], contacts[n_contacts, 1] = index, opened[index]
                    contacts[n_contacts, 2] = t
                    n_contacts += 1
                else:
                    # A contact closing as its overlap falls through zero (e' < 0 at the switch;
                    # closing through g = e + 2 zeta e' instead, it touches at e = -2 zeta e' <
                    # 0 with e' > 0) meets it at zero; found as a root it is zero only to the
                    # rounding of its terms (a ball falling from thousands above: ~1e-12). The
                    # root is taken as exact, as in twoball.kernels.runs.run (docs/accuracy.md,
                    # "The linear stack"). The overlap must have been a gap, or opening, at the
                    # phase's start (e_next, de_next): a ball resting on another at its static
                    # overlap and released within the rounding closes again at once, still
                    # overlapping; lifted to zero it would be released there again, for ever.
                    opening = e_next[index] > 0.0 or de_next[index] > 0.0
                    if de[index] < 0.0 and opening:
                        e[index] = 0.0
                    opened[index] = t
                    if top_apexes == 0:
                        first[index] += 1
                    _begin_unloaded_above(index, t, top_apexes, unloaded, opened, first)
                active[index] = not active[index]
                apex_passed[index] = False
                if index >= 1:
                    apex_passed[index - 1] = False
            elif event == EVENT_APEX:
                de[index] -= de.sum()  # the top ball stops there: its velocity to zero
                apexes[n_apex, 0], apexes[n_apex, 1], apexes[n_apex, 2] = index, t, e.sum()
                n_apex += 1
                top_apexes += 1
                if top_apexes == apexes_wanted:
                    status = STATUS_DONE
                    running = False
                    break
            elif event == EVENT_TIME:
                status = STATUS_DONE
                if tau == np.inf:
                    # run without an end (to an apex) and a phase certified for ever: no
                    # contact switches again and no ball flies, a grounded cluster decaying to
                    # its static rest: at rest from the phase's start (it ended DONE at t = inf,
                    # no apex and no reason: a researcher's trial)
                    status, t = STATUS_REST, phase_start
                running = False
                break
            elif event == EVENT_REST:
                status = STATUS_REST
                running = False
                break
            elif event == EVENT_STEPS:
                status = STATUS_PHASES
                running = False
                break
            else:
                status = STATUS_STUCK
                running = False
                break
    for c in range(n):  # contacts still open at the end end there (an unloaded one never began)
        if active[c] and not unloaded[c]:
            contacts = _room_for_one(contacts, n_contacts)
            contacts[n_contacts, 0], contacts[n_contacts, 1], contacts[n_contacts, 2] = (
                c,
                opened[c],
                t,
            )
            n_contacts += 1
    return StackRun(
        status=status,
        end_time=t,
        apexes=apexes[:n_apex].copy(),
        contacts=contacts[:n_contacts].copy(),
        contacts_first=first,
        phases=phases[:n_phases],
        phase_count=phase_count,
    )


@njit
def _begin_unloaded_above(contact, t, top_apexes, unloaded, opened, first):
    """Contact ``contact`` begins to push at t: the unloaded contacts right above it (balls
    released touching, see :func:`run`) begin with it, each pushed as the ball below it is."""
    above = contact + 1
    while above < unloaded.size and unloaded[above]:
        unloaded[above] = False
        opened[above] = t
        if top_apexes == 0:
            first[above] += 1
        above += 1


@njit
def sample(phases, times, masses, zeta):
    """Exact heights, velocities and contact forces at the given times from the recorded
    phases (their relative states: :func:`run`): arrays (len(times), N) each."""
    n = masses.size
    store = new_clusters(n)
    heights = np.empty((times.size, n))
    speeds = np.empty((times.size, n))
    forces = np.zeros((times.size, n))
    work = new_workspace(n)
    e = np.empty(n)  # the relative state at each time, which sampling does not read
    de = np.empty(n)
    active = np.zeros(n, dtype=np.bool_)
    current = -1
    count = 0
    for s in range(times.size):
        index = max(np.searchsorted(phases[:, 0], times[s], side="right") - 1, 0)
        bits = int(phases[index, 1])
        for c in range(n):
            active[c] = (bits >> c) & 1 == 1
        if index != current:
            if not _clusters_ready(active, store.ready):
                _ensure_clusters(active, store, masses, zeta)
            count = _phase(
                active,
                phases[index, 2 : 2 + n],
                phases[index, 2 + n :],
                store,
                masses,
                zeta,
                work.lo,
                work.hi,
                work.cid,
                work.grounded,
                work.modes,
                work.centre,
                work.size,
                work.speed,
                work.of_ball,
                work.z,
            )
            current = index
        tau = times[s] - phases[index, 0]
        _evaluate(
            tau, count, True, work, store, phases[index, 2 : 2 + n], phases[index, 2 + n :], e, de
        )
        x, v = work.x, work.v
        heights[s] = x
        speeds[s] = v
        for c in range(n):
            if active[c]:
                eta = x[c] - (x[c - 1] if c >= 1 else 0.0)  # sampled: to the heights' rounding
                deta = v[c] - (v[c - 1] if c >= 1 else 0.0)
                forces[s, c] = max(-(eta + 2.0 * zeta[c] * deta), 0.0)
    return heights, speeds, forces
