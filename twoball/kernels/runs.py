"""The two-ball kernel's phase loop (docs/model.md, "Bodies, coordinates, forces"): a drop run
phase by phase (:func:`run`), a block of drops for the sweep (:func:`run_block`) and the exact
state at any times from the recorded phases (:func:`sample`). Each phase is advanced by
:func:`twoball.kernels.phases.advance_phase`."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from twoball.jit import njit
from twoball.kernels.codes import (
    EVENT_APEX,
    EVENT_BALL,
    EVENT_FLOOR,
    EVENT_REST,
    EVENT_STEPS,
    EVENT_TIME,
    MAX_PHASES,
    ROUNDING,
    STATUS_DONE,
    STATUS_PHASES,
    STATUS_REST,
    STATUS_STUCK,
)
from twoball.kernels.phases import (
    BOTH,
    FREE,
    P_NOISE,
    P_Z01,
    P_Z12,
    _rest_size,
    advance_phase,
    constants,
    prepare,
    state_at,
)


class RunOutcome(NamedTuple):
    """What :func:`run` returns (a named tuple inside numba too)."""

    status: int  # a twoball.errors.Status value
    end_time: float
    apex_t: np.ndarray  # (n_apex,) times of the upper ball's apexes
    apex_h: np.ndarray  # (n_apex,) their heights X2
    ball_contacts_first: int  # ball contacts that start before the first apex
    floor_contacts_first: int
    contacts: np.ndarray  # (n, 3): contact, start, end (empty unless recorded)
    # (n, 7): t, kind, x1, eta, v1, eta' at each phase start and the phase's own duration tau
    # (the difference of two rounded start times is not; benchmarks/phase_audit.py needs it);
    # empty unless recorded
    phases: np.ndarray
    phase_count: int  # the run's statistics: phases, certified steps, closed-form root solves
    step_count: int
    root_count: int


@njit
def _room_for_one(rows, n):
    """``rows`` if it has a row free after the first ``n``, else a copy twice as long."""
    if n < rows.shape[0]:
        return rows
    grown = np.empty((max(2 * rows.shape[0], 8), rows.shape[1]))
    grown[:n] = rows[:n]
    return grown


@njit
def run(x1, x2, apexes_wanted, t_end, prepared, record_contacts, record_phases):
    """Run from rest at heights (x1, x2) until the wanted apex, t_end, or rest.

    Returns a :class:`RunOutcome`. Contacts and phases are recorded only when asked (the arrays
    are empty otherwise); the apex table grows as apexes come, so a run to a time with no apex
    limit allocates only what it finds.
    """
    # the state in the relative coordinates of state_at; eta is exact (Sterbenz) for a gap
    # below the drop height
    eta = x2 - x1
    v1 = 0.0
    deta = 0.0
    t = 0.0
    kind = FREE
    # The upper ball's apex is found from its velocity v1 + eta', which after an apex is zero
    # only to rounding; an apex is looked for again only once a ball contact has ended (only
    # the ball contact can lift the upper ball), rather than zeroing eta' there, which would
    # move the overlap's rate by the lower ball's rounding.
    rising = False
    apexes = np.empty((min(apexes_wanted, 64), 2))  # rows: t, h
    n_apex = 0
    ball_first = 0
    floor_first = 0
    start = np.zeros(2)
    contacts = np.empty((64 if record_contacts else 0, 3))
    n_contacts = 0
    phases = np.empty((64 if record_phases else 0, 7))
    n_phases = 0
    status = STATUS_PHASES
    entered_by = -1  # the contact whose switch began the current phase
    # A state that leaves the both-contact phase carries the rounding of its closed form about
    # the static rest (~ mu ulp for a heavy upper ball); later phases must not take that for an
    # overlap, or a contact that just opened closes again at once, for ever.
    stepping = constants(prepared)
    params, y_rest = stepping.params, stepping.y_rest
    both_offset = ROUNDING * params[P_NOISE] * _rest_size(y_rest)
    carried = 0.0
    phase_count = step_count = root_count = 0
    for _ in range(MAX_PHASES):
        if record_phases:
            phases = _room_for_one(phases, n_phases)
            row = phases[n_phases]
            row[0], row[1], row[2], row[3], row[4], row[5] = t, kind, x1, eta, v1, deta
            n_phases += 1
        horizon = t_end - t
        horizon_event = EVENT_TIME
        v2 = v1 + deta
        if rising and (kind & 2) == 0 and v2 > 0.0 and v2 < horizon:
            horizon = v2  # the upper ball flies freely: its apex is exactly v2 away
            horizon_event = EVENT_APEX
        event, tau, x1, eta, v1, deta, steps, roots = advance_phase(
            kind, t, x1, eta, v1, deta, horizon, horizon_event, stepping, entered_by, carried
        )
        phase_count += 1
        step_count += steps
        root_count += roots
        if record_phases:
            phases[n_phases - 1, 6] = tau
        if kind == BOTH:  # the state leaves it with the rounding of its offset (see below)
            carried = both_offset
        entered_by = event if event in (EVENT_FLOOR, EVENT_BALL) else -1
        t += tau
        if event in (EVENT_FLOOR, EVENT_BALL):
            bit = 1 << event
            if kind & bit:
                rising = rising or event == EVENT_BALL
                if record_contacts:
                    contacts = _room_for_one(contacts, n_contacts)
                    row = contacts[n_contacts]
                    row[0], row[1], row[2] = event, start[event], t
                    n_contacts += 1
            else:
                # A contact closing meets its overlap at zero. Found as a root, the overlap there
                # is zero only to the rounding of its terms (the upper ball's fall from thousands
                # above: ~1e-12, where a stiff ball contact's whole compression is ~1): carried
                # into the contact, that start would outweigh every other error of the bounce.
                # So the root is taken as exact (a shift of the switch by rounding / speed).
                if event == EVENT_FLOOR and v1 < 0.0:
                    x1 = 0.0
                elif event == EVENT_BALL and deta < 0.0:
                    eta = 0.0
                start[event] = t
                if n_apex == 0:
                    if event == EVENT_BALL:
                        ball_first += 1
                    else:
                        floor_first += 1
            kind ^= bit
        elif event == EVENT_APEX:
            rising = False
            apexes = _room_for_one(apexes, n_apex)
            apexes[n_apex, 0] = t
            apexes[n_apex, 1] = x1 + eta
            n_apex += 1
            if n_apex == apexes_wanted:
                status = STATUS_DONE
                break
        elif event == EVENT_TIME:
            status = STATUS_DONE
            break
        elif event == EVENT_REST:
            status = STATUS_REST
            break
        elif event == EVENT_STEPS:
            status = STATUS_PHASES
            break
        else:
            status = STATUS_STUCK
            break
    if record_contacts:
        # contacts still open at the end of the run end there
        for contact in range(2):
            if kind & (1 << contact):
                contacts = _room_for_one(contacts, n_contacts)
                row = contacts[n_contacts]
                row[0], row[1], row[2] = contact, start[contact], t
                n_contacts += 1
    return RunOutcome(
        status=status,
        end_time=t,
        apex_t=apexes[:n_apex, 0].copy(),
        apex_h=apexes[:n_apex, 1].copy(),
        ball_contacts_first=ball_first,
        floor_contacts_first=floor_first,
        contacts=contacts[:n_contacts],
        phases=phases[:n_phases],
        phase_count=phase_count,
        step_count=step_count,
        root_count=root_count,
    )


@njit(nogil=True)
def run_block(mu, zeta01, zeta12, x2_0, height, apex_h, apex_t, contacts, status):
    """Run every drop of a block to its second apex, compiled, with the GIL released (the batch
    path of the sweep; docs/model.md, "What is measured").

    mu (nm), zeta01 (ne), zeta12 (ne, nm), x2_0 (ne, nt); outputs (ne, nm, nt): apex_h and
    apex_t with a leading axis of 2, pre-filled with NaN; contacts (ball contacts before the
    first apex, NaN without one) and status (int8, :class:`twoball.errors.Status`). One
    :func:`prepare` serves a whole row of tau_ratio; nothing but apexes and counts is recorded.
    """
    for i in range(x2_0.shape[0]):
        for j in range(mu.shape[0]):
            prepared = prepare(mu[j], zeta01[i], zeta12[i, j])
            for k in range(x2_0.shape[1]):
                outcome = run(height, x2_0[i, k], 2, np.inf, prepared, False, False)
                n_apex = outcome.apex_t.size
                for a in range(n_apex):
                    apex_t[a, i, j, k] = outcome.apex_t[a]
                    apex_h[a, i, j, k] = outcome.apex_h[a]
                contacts[i, j, k] = outcome.ball_contacts_first if n_apex > 0 else np.nan
                status[i, j, k] = outcome.status


@njit
def sample(phases, times, prepared, left=False):
    """Exact state and forces at the given times from the recorded phases.

    At a switch the forces jump (docs/model.md, "Bodies, coordinates, forces"): a time at which
    a phase starts is taken in that phase (the right side), or with ``left`` at the end of the
    phase before it. Returns an array (len(times), 6): x1, x2, v1, v2, f01, f12.
    """
    params, x, x_inv = prepared.params, prepared.x, prepared.x_inv
    blocks, y_rest = prepared.blocks, prepared.y_rest
    z01, z12 = params[P_Z01], params[P_Z12]
    out = np.empty((times.size, 6))
    starts = phases[:, 0]
    for i in range(times.size):
        index = max(np.searchsorted(starts, times[i], side="right") - 1, 0)
        if left and index > 0 and starts[index] == times[i]:
            index -= 1
        row = phases[index]
        kind = int(row[1])
        x1, eta, v1, deta, _, _ = state_at(
            kind,
            times[i] - row[0],
            row[2],
            row[3],
            row[4],
            row[5],
            params,
            x,
            x_inv,
            blocks,
            y_rest,
        )
        f01 = max(-(x1 + 2.0 * z01 * v1), 0.0) if kind & 1 else 0.0
        f12 = max(-(eta + 2.0 * z12 * deta), 0.0) if kind & 2 else 0.0
        row_out = out[i]
        row_out[0], row_out[1], row_out[2], row_out[3] = x1, x1 + eta, v1, v1 + deta
        row_out[4], row_out[5] = f01, f12
    return out


@njit
def run_drop(mu, z01, z12, x1, x2, apexes_wanted, t_end):
    """:func:`prepare` and :func:`run` (contacts recorded, no phases) in one compiled call, so
    that nothing of the preparation crosses into Python (``simulate``'s common path)."""
    return run(x1, x2, apexes_wanted, t_end, prepare(mu, z01, z12), True, False)
