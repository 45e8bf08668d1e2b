"""The certified steps of the compiled Hertz stack (:mod:`twoball.kernels.hertz`; docs/stacks.md,
"How each force is solved"), where a step's series cannot show a switch: the energy, which never
rises, bounds every force for the rest of the run (:func:`force_bounds`); with the contacts
active in a phase that bounds eta'' towards each switch (:func:`_phase_bounds`); each step keeps
eta + eta' h - M h^2 / 2 on its side (:func:`_step_for`), doubled while the forces bounded over
the step itself still certify it (:func:`certified_step`). The method of
:mod:`twoball.stacks.hertz`, ported as it is.
"""

from __future__ import annotations

import math

import numpy as np

from twoball.jit import njit

AHEAD = 4.0  # steps certified at once
STALL = 1e-8  # a contact this close to delta = 0 and delta' = 0 would stall the time change


@njit
def _power(delta: float) -> float:
    """delta^(3/2), delta >= 0 (a square root: pow costs several times more)."""
    return delta * math.sqrt(delta)


@njit
def _weights(masses):
    """W_c, the weight above contact c (its ball's and every ball's above)."""
    n = masses.size
    weights = np.empty(n)
    above = 0.0
    for c in range(n - 1, -1, -1):
        above += masses[c]
        weights[c] = above
    return weights


@njit
def force_bounds(masses, lam, total) -> np.ndarray:
    """F_c >= f_c for the rest of the run, from the energy ``total``, which never rises (the
    argument of twoball.stacks.hertz._force_bounds)."""
    n = masses.size
    weights = _weights(masses)
    wells = 0.6 * weights ** (5.0 / 3.0)
    kinetic = total + wells.sum()
    force = np.empty(n)
    for c in range(n):
        room = total + wells.sum() - wells[c]
        delta = max(weights[c] ** (2.0 / 3.0), 1.0)
        while 0.4 * delta**2.5 - weights[c] * delta <= room:
            delta *= 1.5
        closing = math.sqrt(2.0 * kinetic / masses[c])
        if c >= 1:
            closing += math.sqrt(2.0 * kinetic / masses[c - 1])
        force[c] = delta**1.5 * (1.0 + lam[c] * closing)
    return force


@njit
def _phase_bounds(masses, force, active, both, towards) -> None:
    """Bounds on eta_c'' while the phase lasts (twoball.stacks.hertz._phase_bounds): |eta''| <=
    both, and towards, the bound towards each contact's switch."""
    n = masses.size
    for c in range(n):
        own_force = force[c] if active[c] else 0.0
        own = own_force / masses[c]
        if c >= 1:
            own += own_force / masses[c - 1]
        above = force[c + 1] if c + 1 < n and active[c + 1] else 0.0
        neighbours = above / masses[c]
        if c >= 1:
            below = force[c - 1] if active[c - 1] else 0.0
            neighbours += below / masses[c - 1]
        else:
            neighbours += 1.0  # gravity pulls ball 0 towards the floor
        both[c] = max(own + neighbours, 1e-300)
        toward = (max(own - 1.0, 0.0) if c == 0 else own) if active[c] else neighbours
        towards[c] = max(toward, 1e-300)


@njit
def _rounding(x, deta, t, c) -> float:
    """The rounding of eta_c: 16 ulp of the heights plus eta' times 16 ulp of the clock."""
    heights = 1.0
    for j in range(x.size):
        heights += abs(x[j])
    return 16e-16 * (heights + abs(deta[c]) * (1.0 + abs(t)))


@njit
def _step_for(x, eta, deta, t, bound, active) -> float:
    """The largest h keeping each eta (or -eta, for a contact that pushes) above -tol by
    eta + eta' h - M h^2 / 2 (twoball.stacks.hertz._step_for)."""
    step = math.inf
    for c in range(eta.size):
        value, rate = (-eta[c], -deta[c]) if active[c] else (eta[c], deta[c])
        value = max(value, 0.0) + _rounding(x, deta, t, c)
        root = math.sqrt(rate * rate + 2.0 * bound[c] * value)
        h = (rate + root) / bound[c] if rate >= 0.0 else 2.0 * value / (root - rate)
        step = min(step, h)
    return step


@njit
def _local_forces(masses, lam, eta, deta, active, span, force_bound, both, towards, bound):
    """Bounds F_c (into ``bound``) on each force over the next ``span``, by bootstrap
    (twoball.stacks.hertz._local_forces); the run's bound when the bootstrap does not close."""
    n = masses.size
    for c in range(n):
        delta = max(-eta[c], 0.0)
        bound[c] = min(2.0 * _power(delta) * (1.0 + lam[c] * abs(deta[c])) + 1e-300, force_bound[c])
    for _ in range(6):
        _phase_bounds(masses, bound, active, both, towards)
        holds = True
        for c in range(n):
            delta, speed = max(-eta[c], 0.0), abs(deta[c])
            reach = delta + speed * span + 0.5 * both[c] * span * span
            implied = _power(reach) * (1.0 + lam[c] * (speed + both[c] * span))
            if implied >= bound[c]:
                holds = False
                both[c] = implied  # kept until the bounds are raised below
            else:
                both[c] = -1.0
        if holds:
            return
        capped = True
        for c in range(n):
            if both[c] >= 0.0:
                bound[c] = min(max(bound[c], 1.5 * both[c]), force_bound[c])
            capped = capped and bound[c] == force_bound[c]
        if capped:
            break
    bound[:] = force_bound


@njit
def certified_step(masses, lam, x, eta, deta, t, force_bound, active, wanted, work) -> float:
    """A step over which no overlap changes sign unseen (twoball.stacks.hertz._certified_step): from
    the run's force bounds, then doubled while the forces bounded over the step certify it.
    ``wanted`` (the integrator's next step) is tried first: if certified, it is the answer.
    ``work``: (3, N) scratch; its row 0 is left holding bounds on |eta''| valid over the step
    returned (those of the last bounds tried, over that step or a longer span)."""
    both, towards, local = work[0], work[1], work[2]
    if wanted < math.inf:
        _local_forces(masses, lam, eta, deta, active, wanted, force_bound, both, towards, local)
        _phase_bounds(masses, local, active, both, towards)
        if _step_for(x, eta, deta, t, towards, active) >= wanted:
            return wanted
    _phase_bounds(masses, force_bound, active, both, towards)
    step = _step_for(x, eta, deta, t, towards, active)
    for _ in range(60):
        trial = 2.0 * step
        _local_forces(masses, lam, eta, deta, active, trial, force_bound, both, towards, local)
        _phase_bounds(masses, local, active, both, towards)
        if _step_for(x, eta, deta, t, towards, active) < trial:
            break
        step = trial
    return step


@njit
def _needs_certifying(eta, deta, active, rho_scales, speed_scales) -> bool:
    """Whether a contact's switch could be stepped over unseen by the series alone: an open
    contact still overlapping (clamped, its re-push), or an active one that would stall the time
    change (it is left out of the series, :data:`STALL`). Any other open contact's overlap is
    concave in time (its eta'' is minus its neighbours' forces over their masses, none
    pulling), so if it is open at both ends of a step it is open throughout."""
    for c in range(eta.size):
        if active[c]:
            rho = math.sqrt(max(-eta[c], 0.0))
            if rho <= STALL * rho_scales[c] and deta[c] >= -STALL * speed_scales[c]:
                return True
        elif eta[c] < 0.0:
            return True
    return False


@njit
def _recertified(masses, lam, x, eta, deta, t, force_bound, active, certified, h_abs, work, bounds):
    """The end of a certified span (:func:`certified_step`) holding at t,
    a span certified before reused (it holds for every step inside it), else a few steps
    ahead certified at once; ``bounds`` holds |eta''| bounds over it."""
    if t + h_abs > certified:
        span = certified_step(
            masses, lam, x, eta, deta, t, force_bound, active, AHEAD * h_abs, work
        )
        certified = t + span
        bounds[:] = work[0]
    return certified
