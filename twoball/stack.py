"""Stacks of N balls with linear contacts, solved exactly phase by phase (docs/model.md, "Stacks
of N balls").

The two-ball solver of :mod:`twoball.exact`, generalised. In a phase a set of contacts is
active; it splits the stack into *clusters*, runs of balls joined by active ball contacts. A
cluster resting on the floor through an active floor contact is *grounded*.

- A cluster's shape is given by the overlaps eta_c of its active contacts. They obey
  eta'' = -W (eta - eta_rest + 2 Z eta') with W = D M^-1 D^T (D maps heights to overlaps, M is
  diagonal in the masses, Z in the damping ratios): the state z = (eta - eta_rest, eta') of a
  cluster with k active contacts satisfies z' = B z, B = [[0, I], [-W, -W 2Z]]. eta_rest is the
  static compression under the weight above each contact (grounded) or zero (free clusters).
- A free cluster's centre of mass is a parabola; a ball on its own is one.
- z' = B z is solved in closed form through a real block-diagonal form
  B = X diag(B_1..B_k) X^-1 with 2x2 blocks, each advanced exactly on every damping branch
  (:func:`twoball.exact._block_flow`).
  One contact: X = I. Two contacts: the refined mode split of the two-ball solver
  (:func:`twoball.exact._split_modes`). More: eigenvectors, complex pairs as rotations and real
  eigenvalues paired in order; a near-defective pair then costs accuracy in proportion to the
  condition of X, which the tolerance carries.

Why no contact can be missed: the certified steps of :mod:`twoball.exact`. Every switching
function is linear in the heights and velocities of at most two balls; its second derivative is
a constant (from gravity, for balls of free clusters) plus a linear form in each involved
cluster's w = z' (which obeys the same equation as z). In the block coordinates X^-1 w that form
is a sum over the blocks, and each block's share is bounded for the rest of the phase by sizes
of its state that never grow (a rotation's norm, a diagonal's entries, a strongly overdamped
block's two exponentials, else its oscillator energy): :func:`_block_weights`. So each step
keeps F + F' h - bound h^2/2 above -tol, and a root can be approached but not stepped over.
Bounding mode by mode, as the two-ball solver does, steps each contact at the pace of the modes
that move it: the cluster's total energy weighs a light top ball's contact by 1/sqrt(its mass)
times the whole stack's motion.

A stack is at rest when every contact is active and the same per-mode bounds, on z, leave every
contact force above zero for ever, beyond the rounding of the phase's start
(:func:`_rest_rounding`): docs/stacks.md, "Why every damped stack ends", has the argument.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from twoball import exact
from twoball.errors import ParameterError, SolverError, Status, phase_limit_hint
from twoball.exact import ROUNDING
from twoball.jit import njit
from twoball.model import (
    DEFAULT_HEIGHT,
    MASS_RATIO_RANGE,
    RESOLUTION,
    chain_rounding_ratio,
    check_value,
    decay_ratio,
    domain_error,
    floor_contact_time,
)
from twoball.observables import as_times, check_span
from twoball.solve import stop_rule

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
MAX_STEPS_PER_PHASE = 100_000
MAX_PHASES = 1_000_000

# Events of one phase.
EV_SWITCH, EV_APEX, EV_TIME, EV_REST, EV_STUCK, EV_STEPS = 0, 1, 2, 3, 4, 5
STATUS_DONE, STATUS_REST = int(Status.DONE), int(Status.REST)
STATUS_STUCK, STATUS_PHASES = int(Status.STUCK), int(Status.PHASE_LIMIT)
# How a block's future is bounded (:func:`_block_kind`).
BLOCK_ROTATION, BLOCK_DIAGONAL, BLOCK_EXPONENTIALS, BLOCK_ENERGY = 0, 1, 2, 3


class Clusters(NamedTuple):
    """Every cluster's closed form, built on first use (cluster id from :func:`_cluster_id`)."""

    ready: np.ndarray  # (ids,) bool
    contacts: np.ndarray  # (ids,) active contacts k
    x: np.ndarray  # (ids, 2N, 2N) X of the block form (first 2k rows and columns)
    x_inv: np.ndarray
    blocks: np.ndarray  # (ids, N, 2, 2)
    kind: np.ndarray  # (ids, N) how each block's future is bounded (BLOCK_ROTATION, ...)
    companion: np.ndarray  # (ids, N, 2, 2) (u, u') = R y of a block (BLOCK_ENERGY, _EXPONENTIALS)
    rates: np.ndarray  # (ids, N, 2) slow and fast decay rates (BLOCK_EXPONENTIALS)
    eta_rest: np.ndarray  # (ids, N) by local contact
    shape: np.ndarray  # (ids, N, N) ball (local) height from z_1 (contact local)
    offset: np.ndarray  # (ids, N) ball height at z = 0 (grounded), 0 for free clusters
    # weights (ids, N, N, 2) of each functional on each block's sizes (:func:`_block_weights`):
    # per ball, x'' and the g'' of its lower and upper contact, on w = z'; per active contact,
    # eta'' and g'' on w and g - g_rest on z
    w_x2: np.ndarray
    w_g_low: np.ndarray
    w_g_up: np.ndarray
    w_eta: np.ndarray
    w_g: np.ndarray
    w_rest: np.ndarray
    noise: np.ndarray  # (ids,) condition of X


@njit
def _cluster_id(lo, hi, grounded, n):
    """Index of the cluster of balls lo..hi (grounded ones have lo = 0)."""
    return n * n + hi if grounded else lo * n + hi


@njit
def new_clusters(n):
    """Empty storage for every cluster of an n-ball stack."""
    ids = n * n + n
    d = 2 * n
    return Clusters(
        np.zeros(ids, dtype=np.bool_),
        np.zeros(ids, dtype=np.int64),
        np.zeros((ids, d, d)),
        np.zeros((ids, d, d)),
        np.zeros((ids, n, 2, 2)),
        np.zeros((ids, n), dtype=np.int64),
        np.zeros((ids, n, 2, 2)),
        np.zeros((ids, n, 2)),
        np.zeros((ids, n)),
        np.zeros((ids, n, n)),
        np.zeros((ids, n)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros((ids, n, n, 2)),
        np.zeros(ids),
    )


@njit
def _real_blocks(b, k):
    """X, X^-1 and k 2x2 blocks with B = X diag(blocks) X^-1 (see the module docstring)."""
    d = 2 * k
    x = np.zeros((d, d))
    blocks = np.zeros((k, 2, 2))
    if k == 1:
        x[0, 0] = x[1, 1] = 1.0
        blocks[0] = b
        return x, x.copy(), blocks
    if k == 2:
        x4, x4_inv, blocks2 = exact._split_modes(b)
        return x4, x4_inv, blocks2
    lam, vec = np.linalg.eig(b.astype(np.complex128))
    scale = np.abs(lam).max()
    used = np.zeros(d, dtype=np.bool_)
    count = 0
    for i in range(d):
        if used[i] or abs(lam[i].imag) <= 1e-12 * scale:
            continue
        partner, gap = -1, np.inf
        for j in range(d):
            if j != i and not used[j] and abs(lam[j] - np.conj(lam[i])) < gap:
                partner, gap = j, abs(lam[j] - np.conj(lam[i]))
        used[i] = used[partner] = True
        top = i if lam[i].imag > 0.0 else partner
        x[:, 2 * count] = vec[:, top].real
        x[:, 2 * count + 1] = vec[:, top].imag
        re, im = lam[top].real, lam[top].imag
        blocks[count, 0, 0], blocks[count, 0, 1] = re, im
        blocks[count, 1, 0], blocks[count, 1, 1] = -im, re
        count += 1
    real_index = np.array([i for i in range(d) if not used[i]], dtype=np.int64)
    order = real_index[np.argsort(lam[real_index].real)]
    for p in range(0, order.size, 2):
        for q in range(2):
            v = vec[:, order[p + q]]
            big = np.argmax(np.abs(v))
            phase = np.conj(v[big]) / abs(v[big])  # a real eigenvector times a phase
            x[:, 2 * count + q] = (v * phase).real
        blocks[count, 0, 0] = lam[order[p]].real
        blocks[count, 1, 1] = lam[order[p + 1]].real
        count += 1
    return x, np.linalg.inv(x), blocks


@njit
def _block_kind(block):
    """How a 2x2 block's future is bounded (docs/stacks.md, "Why every damped stack ends"):
    a scaled rotation (a complex pair of the eigenvector form), a diagonal (two real
    eigenvalues), a strongly overdamped block (two exponentials) or, otherwise, the energy of
    its oscillator."""
    if block[0, 1] == 0.0 and block[1, 0] == 0.0:
        return BLOCK_DIAGONAL
    if block[0, 0] == block[1, 1] and block[0, 1] == -block[1, 0]:
        return BLOCK_ROTATION
    if exact._overdamped_rates(block)[1] > 0.0:
        return BLOCK_EXPONENTIALS
    return BLOCK_ENERGY


@njit
def _block_weights(kind, block, companion, rates, r0, r1):
    """(p, q) with |r . y(s)| <= p a + q b for every later time s of the phase, where
    (a, b) = :func:`_sizes` of the block's state y now (docs/stacks.md, "Why every damped
    stack ends"). A rotation keeps |y| or shrinks it, a diagonal each |y_i|; a strongly
    overdamped block is two decaying exponentials (:func:`twoball.exact._overdamped_bound`);
    otherwise Cauchy-Schwarz on the oscillator energy of (u, u') = R y, which never rises."""
    if kind == BLOCK_ROTATION:
        return math.hypot(r0, r1), 0.0
    if kind == BLOCK_DIAGONAL:
        return abs(r0), abs(r1)
    row = np.empty(2)
    row[0], row[1] = r0, r1
    alpha_beta = exact._companion_row(row, companion)
    alpha, beta = alpha_beta[0], alpha_beta[1]
    if kind == BLOCK_EXPONENTIALS:
        slow, fast = rates[0], rates[1]
        return (
            abs(alpha - beta * slow) * exact.OVERDAMPED_SAFETY,
            abs(alpha - beta * fast) * exact.OVERDAMPED_SAFETY,
        )
    omega = math.sqrt(block[0, 0] * block[1, 1] - block[0, 1] * block[1, 0])
    return math.hypot(alpha / omega, beta), 0.0


@njit
def _store_weights(target, store, cid, index, row, k):
    """target[cid, index] = the weights of the functional ``row`` (on z or w, length 2k) on
    each block of the cluster: row X restricted to the block, through :func:`_block_weights`."""
    x = store.x[cid]
    for blk in range(k):
        r0 = r1 = 0.0
        for m in range(2 * k):
            r0 += row[m] * x[m, 2 * blk]
            r1 += row[m] * x[m, 2 * blk + 1]
        p, q = _block_weights(
            store.kind[cid, blk],
            store.blocks[cid, blk],
            store.companion[cid, blk],
            store.rates[cid, blk],
            r0,
            r1,
        )
        target[cid, index, blk, 0] = p
        target[cid, index, blk, 1] = q


@njit
def _build_cluster(store, cid, lo, hi, grounded, masses, zeta):
    """Fill ``store`` at ``cid`` for the cluster of balls lo..hi (docs/model.md, "Stacks of N
    balls")."""
    n = masses.size
    first = 0 if grounded else lo + 1  # its first active contact
    k = hi - first + 1
    balls = hi - lo + 1
    store.contacts[cid] = k
    if k == 0:
        store.ready[cid] = True
        store.noise[cid] = 1.0
        return
    # W = D M^-1 D^T on the active contacts (contact c joins balls c-1 and c)
    w = np.zeros((k, k))
    for i in range(k):
        c = first + i
        w[i, i] = 1.0 / masses[c] + (1.0 / masses[c - 1] if c >= 1 else 0.0)
        if i + 1 < k:
            w[i, i + 1] = w[i + 1, i] = -1.0 / masses[c]
    b = np.zeros((2 * k, 2 * k))
    for i in range(k):
        b[i, k + i] = 1.0
        for j in range(k):
            b[k + i, j] = -w[i, j]
            b[k + i, k + j] = -w[i, j] * 2.0 * zeta[first + j]
    x, x_inv, blocks = _real_blocks(b, k)
    store.x[cid, : 2 * k, : 2 * k] = x
    store.x_inv[cid, : 2 * k, : 2 * k] = x_inv
    store.blocks[cid, :k] = blocks
    store.noise[cid] = np.abs(x).sum(axis=0).max() * np.abs(x_inv).sum(axis=0).max()
    for blk in range(k):
        kind = _block_kind(blocks[blk])
        store.kind[cid, blk] = kind
        if kind in (BLOCK_ENERGY, BLOCK_EXPONENTIALS):
            store.companion[cid, blk] = exact._companion(np.ascontiguousarray(blocks[blk]))
        if kind == BLOCK_EXPONENTIALS:
            store.rates[cid, blk] = exact._overdamped_rates(blocks[blk])
    # heights from the shape: x_j = offset_j + shape[j] . z_1 (+ centre of mass if free)
    total = masses[lo : hi + 1].sum()
    for jl in range(balls):
        j = lo + jl
        for i in range(k):
            c = first + i
            if grounded:
                store.shape[cid, jl, i] = 1.0 if c <= j else 0.0
            else:
                above = masses[c : hi + 1].sum()
                store.shape[cid, jl, i] = (1.0 if c <= j else 0.0) - above / total
    if grounded:
        for i in range(k):
            store.eta_rest[cid, i] = -masses[i : hi + 1].sum()  # the weight above contact i
        for jl in range(balls):
            store.offset[cid, jl] = store.eta_rest[cid, : jl + 1].sum()
    b2 = b @ b
    for jl in range(balls):
        j = lo + jl
        row = np.zeros(2 * k)
        row[:k] = store.shape[cid, jl, :k]
        r1 = row @ b  # x'' = r1 . w
        r2 = row @ b2  # x''' = r2 . w
        _store_weights(store.w_x2, store, cid, jl, r1, k)
        _store_weights(store.w_g_low, store, cid, jl, r1 + 2.0 * zeta[j] * r2, k)
        above = zeta[j + 1] if j + 1 < n else 0.0
        _store_weights(store.w_g_up, store, cid, jl, r1 + 2.0 * above * r2, k)
    for i in range(k):
        c = first + i
        row = np.zeros(2 * k)
        row[i] = 1.0
        _store_weights(store.w_eta, store, cid, i, row @ b, k)
        row[k + i] = 2.0 * zeta[c]
        _store_weights(store.w_g, store, cid, i, row @ b, k)
        _store_weights(store.w_rest, store, cid, i, row, k)  # g - g_rest on z
    store.ready[cid] = True


class Phase(NamedTuple):
    """The clusters of one phase and their state at its start."""

    count: int
    lo: np.ndarray  # (N,) per phase cluster
    hi: np.ndarray
    cid: np.ndarray
    grounded: np.ndarray
    modes: np.ndarray  # (N, 2N) X^-1 z at the start
    centre: np.ndarray  # (N, 2) centre of mass height and velocity (free clusters)
    size: np.ndarray  # (N,) rounding scale of heights
    speed: np.ndarray  # (N,) rounding scale of velocities
    of_ball: np.ndarray  # (N,) the phase cluster of each ball


@njit
def _phase(active, x, v, store, masses, zeta):
    """Split the stack into clusters for this set of active contacts; their modes at the start."""
    n = masses.size
    lo = np.zeros(n, dtype=np.int64)
    hi = np.zeros(n, dtype=np.int64)
    cid = np.zeros(n, dtype=np.int64)
    grounded = np.zeros(n, dtype=np.bool_)
    modes = np.zeros((n, 2 * n))
    centre = np.zeros((n, 2))
    size = np.zeros(n)
    speed = np.zeros(n)
    of_ball = np.zeros(n, dtype=np.int64)
    z = np.empty(2 * n)
    eta_rest, x_inv = store.eta_rest, store.x_inv
    count = 0
    j = 0
    while j < n:
        start = j
        while j + 1 < n and active[j + 1]:
            j += 1
        lo[count], hi[count] = start, j
        grounded[count] = start == 0 and active[0]
        cid[count] = _cluster_id(start, j, grounded[count], n)
        if not store.ready[cid[count]]:
            _build_cluster(store, cid[count], start, j, grounded[count], masses, zeta)
        here = cid[count]
        k = store.contacts[here]
        first = 0 if grounded[count] else start + 1
        total = mass_x = mass_v = 0.0
        size[count] = 1.0
        for ball in range(start, j + 1):  # loops, not slices or temporaries (see _evaluate)
            total += masses[ball]
            mass_x += masses[ball] * x[ball]
            mass_v += masses[ball] * v[ball]
            of_ball[ball] = count
            size[count] += abs(x[ball])
            speed[count] += abs(v[ball])
        centre[count, 0] = mass_x / total
        centre[count, 1] = mass_v / total
        for i in range(k):
            c = first + i
            below_x = x[c - 1] if c >= 1 else 0.0
            below_v = v[c - 1] if c >= 1 else 0.0
            z[i] = x[c] - below_x - eta_rest[here, i]
            z[k + i] = v[c] - below_v
            size[count] += abs(eta_rest[here, i])
        for row in range(2 * k):  # modes = X^-1 z
            total = 0.0
            for col in range(2 * k):
                total += x_inv[here, row, col] * z[col]
            modes[count, row] = total
        count += 1
        j += 1
    return Phase(count, lo, hi, cid, grounded, modes, centre, size, speed, of_ball)


@njit
def _evaluate(tau, phase, store, n, x, v, a, shape_z, shape_w, mode_z, mode_w):
    """Heights, velocities, accelerations of every ball at tau into the phase (into x, v, a),
    each phase cluster's z and w = z' (into shape_z, shape_w) and their block (mode)
    coordinates X^-1 z and X^-1 w (into mode_z, mode_w)."""
    _evaluate_arrays(
        tau,
        phase.count,
        phase.cid,
        phase.lo,
        phase.hi,
        phase.grounded,
        phase.centre,
        phase.modes,
        store.contacts,
        store.blocks,
        store.x,
        store.shape,
        store.offset,
        x,
        v,
        a,
        shape_z,
        shape_w,
        mode_z,
        mode_w,
    )


@njit
def _evaluate_arrays(
    tau,
    count,
    cids,
    lows,
    highs,
    grounded,
    centre,
    modes,
    contacts,
    blocks,
    big_x,
    shape,
    offset,
    x,
    v,
    a,
    shape_z,
    shape_w,
    mode_z,
    mode_w,
):
    """:func:`_evaluate` on the phase's and the store's arrays, passed one by one: the step
    loop reads them once per phase. Written without array slices or tuples of arrays: each
    would count references, which took most of the time of a step."""
    for p in range(count):
        cid = cids[p]
        k = contacts[cid]
        d = 2 * k
        for row in range(d):
            shape_z[p, row] = 0.0
            shape_w[p, row] = 0.0
        for blk in range(k):
            n0, n1, r0, r1 = exact._flow(
                blocks[cid, blk, 0, 0],
                blocks[cid, blk, 0, 1],
                blocks[cid, blk, 1, 0],
                blocks[cid, blk, 1, 1],
                modes[p, 2 * blk],
                modes[p, 2 * blk + 1],
                tau,
            )
            mode_z[p, 2 * blk], mode_z[p, 2 * blk + 1] = n0, n1
            mode_w[p, 2 * blk], mode_w[p, 2 * blk + 1] = r0, r1
            for row in range(d):  # z = X flow, w = X rate, without allocating
                left, right = big_x[cid, row, 2 * blk], big_x[cid, row, 2 * blk + 1]
                shape_z[p, row] += left * n0 + right * n1
                shape_w[p, row] += left * r0 + right * r1
        if grounded[p]:
            base_x = base_v = base_a = 0.0
        else:
            base_x = centre[p, 0] + tau * (centre[p, 1] - 0.5 * tau)
            base_v = centre[p, 1] - tau
            base_a = -1.0
        for ball in range(lows[p], highs[p] + 1):
            jl = ball - lows[p]
            xs = vs = acc = 0.0
            for i in range(k):
                coefficient = shape[cid, jl, i]
                xs += coefficient * shape_z[p, i]
                vs += coefficient * shape_z[p, k + i]
                acc += coefficient * shape_w[p, k + i]
            x[ball] = base_x + offset[cid, jl] + xs
            v[ball] = base_v + vs
            a[ball] = base_a + acc


@njit
def _sizes(kinds, blocks, companions, rates, cid, k, modes, p, out):
    """The two sizes of each block's state y = modes[p] (cluster cid, k blocks) that
    :func:`_block_weights` weighs, into out[p]: |y| (rotation), |y_0| and |y_1| (diagonal), the
    amplitudes of the slow and the fast exponential (strongly overdamped), sqrt(2 E) =
    sqrt(u'^2 + det(B) u^2) (otherwise). None of them can grow. Whole arrays and indices, not
    slices (see :func:`_evaluate`)."""
    for blk in range(k):
        kind = kinds[cid, blk]
        y0, y1 = modes[p, 2 * blk], modes[p, 2 * blk + 1]
        if kind == BLOCK_ROTATION:
            out[p, blk, 0], out[p, blk, 1] = math.hypot(y0, y1), 0.0
        elif kind == BLOCK_DIAGONAL:
            out[p, blk, 0], out[p, blk, 1] = abs(y0), abs(y1)
        else:
            u = companions[cid, blk, 0, 0] * y0 + companions[cid, blk, 0, 1] * y1
            du = companions[cid, blk, 1, 0] * y0 + companions[cid, blk, 1, 1] * y1
            if kind == BLOCK_EXPONENTIALS:
                slow, fast = rates[cid, blk, 0], rates[cid, blk, 1]
                gap = fast - slow
                out[p, blk, 0] = abs((du + fast * u) / gap)
                out[p, blk, 1] = abs((du + slow * u) / gap)
            else:
                det = (
                    blocks[cid, blk, 0, 0] * blocks[cid, blk, 1, 1]
                    - blocks[cid, blk, 0, 1] * blocks[cid, blk, 1, 0]
                )
                out[p, blk, 0], out[p, blk, 1] = math.sqrt(du * du + det * u * u), 0.0


@njit
def _bounds(
    count,
    cids,
    lows,
    highs,
    grounded,
    contacts,
    kinds,
    blocks,
    companions,
    rates,
    w_x2,
    w_g_low,
    w_g_up,
    w_eta,
    w_g,
    mode_w,
    sizes_w,
    out,
):
    """Every bound on a switching function's curvature for the rest of the phase, from the
    blocks' sizes of w (:func:`_sizes`, into sizes_w): out[ball] holds those of x'' and of the
    g'' of the ball's lower and upper contact, out[contact, 3:5] those of eta'' and g'' of an
    active contact. One call per step (see :func:`_evaluate_arrays`)."""
    for p in range(count):
        cid = cids[p]
        k = contacts[cid]
        _sizes(kinds, blocks, companions, rates, cid, k, mode_w, p, sizes_w)
        for ball in range(lows[p], highs[p] + 1):
            jl = ball - lows[p]
            out[ball, 0] = _bound(w_x2, cid, jl, sizes_w, p, k)
            out[ball, 1] = _bound(w_g_low, cid, jl, sizes_w, p, k)
            out[ball, 2] = _bound(w_g_up, cid, jl, sizes_w, p, k)
        first = 0 if grounded[p] else lows[p] + 1
        for i in range(k):
            out[first + i, 3] = _bound(w_eta, cid, i, sizes_w, p, k)
            out[first + i, 4] = _bound(w_g, cid, i, sizes_w, p, k)


@njit
def _bound(weights, cid, index, sizes, p, k):
    """sum over the k blocks of p a + q b, (p, q) = weights[cid, index, block] and (a, b) =
    sizes[p, block]: a bound on a functional for the rest of the phase (:func:`_block_weights`)."""
    total = 0.0
    for blk in range(k):
        total += weights[cid, index, blk, 0] * sizes[p, blk, 0]
        total += weights[cid, index, blk, 1] * sizes[p, blk, 1]
    return total


@njit
def _rest_rounding(store, cid, x, v, carried):
    """Per contact, a bound (in units of ROUNDING) on how far the rounding of this phase's
    start moves g - g_rest at any later time (docs/stacks.md, "Why every damped stack ends").

    The start z = (eta - eta_rest, eta') is formed from the heights, each overlap rounded to
    ~|x_c| + |x_(c-1)| + |eta_rest| (and what earlier closed forms ``carried``), each rate to
    ~|v_c| + |v_(c-1)|; its modes X^-1 z then carry at most |X^-1| times that, and a mode's
    error is a state of the same block, bounded for all later times as the mode is
    (:func:`_block_weights`). Only for the eigenvector form (rotations and diagonals), that
    is clusters of three or more contacts. Far tighter than the condition of X times the
    heights: a light top ball's weight (1e-9 of ball 0) is below that, not below this."""
    n = store.contacts[cid]
    scale = np.zeros(2 * n)
    for c in range(n):
        scale[c] = abs(x[c]) + abs(store.eta_rest[cid, c]) + 2.0 * carried / ROUNDING
        scale[n + c] = abs(v[c])
        if c >= 1:
            scale[c] += abs(x[c - 1])
            scale[n + c] += abs(v[c - 1])
    spread = np.zeros((1, 2 * n))
    spread[0] = np.abs(store.x_inv[cid, : 2 * n, : 2 * n]) @ scale
    sizes = np.zeros((1, n, 2))
    _sizes(store.kind, store.blocks, store.companion, store.rates, cid, n, spread, 0, sizes)
    out = np.empty(n)
    for c in range(n):
        out[c] = _bound(store.w_rest, cid, c, sizes, 0, n)
    return out


@njit
def advance_phase(
    t, x0, v0, active, horizon, horizon_ball, store, masses, zeta, entered_by, carried, pair
):
    """Advance one phase, started at time t, to its first event.

    Returns (event, index, tau, x, v): a contact switch (index the contact), an apex (index the
    ball; horizon_ball's apex is ``horizon`` away, or -1 for the end of the run), the end, rest,
    a stuck root finder or the step limit. ``pair`` is :func:`twoball.exact.prepare` of a
    two-ball stack (a placeholder for more balls): its rest proof is used for N = 2.
    """
    n = masses.size
    phase = _phase(active, x0, v0, store, masses, zeta)
    x = np.empty(n)
    v = np.empty(n)
    a = np.empty(n)
    shape_z = np.zeros((n, 2 * n))
    shape_w = np.zeros((n, 2 * n))
    mode_z = np.zeros((n, 2 * n))
    mode_w = np.zeros((n, 2 * n))
    sizes_w = np.zeros((n, n, 2))
    sizes_z = np.zeros((1, n, 2))
    curvature = np.zeros((n, 5))  # see _bounds
    # the store's and the phase's arrays, read once (see _evaluate)
    kinds, blocks, companions, rates = store.kind, store.blocks, store.companion, store.rates
    contacts, noise, eta_rest = store.contacts, store.noise, store.eta_rest
    w_x2, w_g_low, w_g_up = store.w_x2, store.w_g_low, store.w_g_up
    w_eta, w_g, w_rest = store.w_eta, store.w_g, store.w_rest
    cids, lows, grounded, of_ball = phase.cid, phase.lo, phase.grounded, phase.of_ball
    sizes, speeds = phase.size, phase.speed
    count, highs, centre, modes = phase.count, phase.hi, phase.centre, phase.modes
    big_x, shape, offset = store.x, store.shape, store.offset
    everything = phase.count == 1 and phase.grounded[0] and store.contacts[phase.cid[0]] == n
    rest_rounding = np.zeros(n)
    if everything and n >= 3:
        rest_rounding = _rest_rounding(store, phase.cid[0], x0, v0, carried)
    tau = 0.0
    last_step = 0.0
    for _ in range(MAX_STEPS_PER_PHASE):
        _evaluate_arrays(
            tau,
            count,
            cids,
            lows,
            highs,
            grounded,
            centre,
            modes,
            contacts,
            blocks,
            big_x,
            shape,
            offset,
            x,
            v,
            a,
            shape_z,
            shape_w,
            mode_z,
            mode_w,
        )
        _bounds(
            count,
            cids,
            lows,
            highs,
            grounded,
            contacts,
            kinds,
            blocks,
            companions,
            rates,
            w_x2,
            w_g_low,
            w_g_up,
            w_eta,
            w_g,
            mode_w,
            sizes_w,
            curvature,
        )
        clock = 1.0 + t + tau
        step = horizon - tau
        event, best = -1, np.inf
        for c in range(n):
            upper = of_ball[c]
            cid_u = cids[upper]
            k_u = contacts[cid_u]
            noise_u = noise[cid_u]
            tol_state = noise_u * (sizes[upper] + speeds[upper] * (1.0 + tau) + tau * tau)
            tol_rate = noise_u * (speeds[upper] + 1.0 + tau)
            if active[c]:
                i = c - (0 if grounded[upper] else lows[upper] + 1)
                eta = eta_rest[cid_u, i] + shape_z[upper, i]
                deta = shape_z[upper, k_u + i]
                ddeta = shape_w[upper, k_u + i]
                bound_eta, bound_g = curvature[c, 3], curvature[c, 4]
            else:
                rigid_u = 0.0 if grounded[upper] else -1.0
                bound_eta, bound_g = curvature[c, 0], curvature[c, 1]
                if c == 0:
                    eta, deta, ddeta = x[0], v[0], a[0]
                    rigid = -rigid_u
                else:
                    lower = of_ball[c - 1]
                    cid_l = cids[lower]
                    eta, deta, ddeta = x[c] - x[c - 1], v[c] - v[c - 1], a[c] - a[c - 1]
                    rigid_l = 0.0 if grounded[lower] else -1.0
                    rigid = abs(rigid_u - rigid_l)
                    bound_eta += curvature[c - 1, 0]
                    bound_g += curvature[c - 1, 2]
                    tol_state += noise[cid_l] * (
                        sizes[lower] + speeds[lower] * (1.0 + tau) + tau * tau
                    )
                    tol_rate += noise[cid_l] * (speeds[lower] + 1.0 + tau)
                bound_eta += rigid
                bound_g += rigid
            tol_state = ROUNDING * tol_state + carried
            value, rate, tol, h = exact.contact_switch(
                active[c], eta, deta, ddeta, zeta[c], bound_eta, bound_g, tol_state, clock
            )
            fresh = c == entered_by and tau == 0.0
            # a rate within the rounding of the velocities has no sign: balls moving together
            # (touching, unloaded) would otherwise switch on and off with the rounding
            tol_rate = ROUNDING * tol_rate * (1.0 + 2.0 * zeta[c])
            if value <= -tol or (value <= tol and rate < -tol_rate and not fresh):
                shift = 0.0  # one Newton correction, as in twoball.exact.advance_phase
                if rate < 0.0:
                    shift = min(max(value / -rate, -last_step), h)
                if c == entered_by and tau + shift <= 0.0:
                    shift = 0.0
                if tau + shift < best:
                    best, event = tau + shift, c
            else:
                step = min(step, h)
        if event >= 0:
            _evaluate_arrays(
                best,
                count,
                cids,
                lows,
                highs,
                grounded,
                centre,
                modes,
                contacts,
                blocks,
                big_x,
                shape,
                offset,
                x,
                v,
                a,
                shape_z,
                shape_w,
                mode_z,
                mode_w,
            )
            return EV_SWITCH, event, best, x, v
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
                margin_ok = _pair_at_rest(pair, x, v, phase.size[0], phase.speed[0], tau, carried)
            if margin_ok:
                return EV_REST, -1, tau, x, v
        if tau + step >= horizon:
            _evaluate_arrays(
                horizon,
                count,
                cids,
                lows,
                highs,
                grounded,
                centre,
                modes,
                contacts,
                blocks,
                big_x,
                shape,
                offset,
                x,
                v,
                a,
                shape_z,
                shape_w,
                mode_z,
                mode_w,
            )
            if horizon_ball >= 0:
                return EV_APEX, horizon_ball, horizon, x, v
            return EV_TIME, -1, horizon, x, v
        if not 0.0 < step < np.inf:
            return EV_STUCK, -1, tau, x0.copy(), v0.copy()
        tau += step
        last_step = step
    return EV_STEPS, -1, tau, x0.copy(), v0.copy()


@njit
def _pair_at_rest(pair, x, v, size, speed, tau, carried):
    """Rest of two balls, both contacts active, proven as :func:`twoball.exact.run` proves it
    (docs/model.md, "What is measured"): per mode, with the tight bound of a strongly overdamped
    mode (:func:`twoball.exact._overdamped_bound`). The cluster's total energy, which the test
    above uses, bounds a slow overdamped mode far too loosely (eps = 0.01 under a heavy upper
    ball: rest proven at t = 3310 by twoball.simulate, never by that energy)."""
    params, _, _, _, rest, _, x_inv, blocks, companions, y_rest, rates, mode_rows = pair
    # the two-ball solver's state is in its relative coordinates (x1, eta, v1, eta')
    eta, deta = x[1] - x[0], v[1] - v[0]
    block_states = exact._block_states(x[0], eta, v[0], deta, x_inv, companions, y_rest)
    roots = exact._energy_roots(exact.BOTH, v[0], deta, 0.0, 0.0, params, blocks, block_states)
    offset = exact._rest_size(y_rest)
    tol = ROUNDING * params[exact.P_NOISE] * (size + offset + speed * (1.0 + tau) + tau * tau)
    return exact._at_rest(roots, params, rest, rates, mode_rows, block_states, tol + carried)


class StackRun(NamedTuple):
    """What :func:`run` returns."""

    status: int
    end_time: float
    apexes: np.ndarray  # (n, 3): ball, t, height, in order
    contacts: np.ndarray  # (n, 3): contact, start, end
    contacts_first: np.ndarray  # (N,) intervals of each contact that start before h1
    phases: np.ndarray  # (n, 2 + 2N): t, active bits, heights, velocities (if recorded)


@njit
def run(masses, zeta, x_start, apexes_wanted, t_end, record_phases, store):
    """Run a stack from rest at heights ``x_start`` until the top ball's ``apexes_wanted``-th
    apex, ``t_end`` or rest (docs/model.md, "Stacks of N balls"). ``store`` holds the clusters'
    closed forms for these masses and damping ratios (:func:`new_clusters`, or one that earlier
    runs of the same balls filled: :func:`_store_for`)."""
    n = masses.size
    x = x_start.copy()
    v = np.zeros(n)
    # Balls released touching (a gap of zero) start with their contact active and unloaded
    # (force zero either way): left inactive, the compression wave of the first impact reaches
    # it as a tangency of high order (eta ~ -(t - t0)^6 for the fourth contact), which rounding
    # toggles on and off for ever. Active, the contact simply starts to push.
    active = np.zeros(n, dtype=np.bool_)
    opened = np.zeros(n)
    first = np.zeros(n, dtype=np.int64)
    for c in range(1, n):
        if x_start[c] == x_start[c - 1]:
            active[c] = True
            first[c] = 1
    t = 0.0
    apexes = np.empty((8, 3))
    n_apex = 0
    top_apexes = 0
    contacts = np.empty((16, 3))
    n_contacts = 0
    phases = np.empty((16 if record_phases else 0, 2 + 2 * n))
    n_phases = 0
    status = STATUS_PHASES
    entered_by = -1
    carried = 0.0
    # the two-ball solver's rest proof, for N = 2 (for more balls a placeholder of the same type)
    pair = exact.prepare(masses[1] if n == 2 else 1.0, zeta[0], zeta[1] if n == 2 else 0.1)
    for _ in range(MAX_PHASES):
        if record_phases:
            phases = exact._room_for_one(phases, n_phases)
            bits = 0
            for c in range(n):
                if active[c]:
                    bits += 1 << c
            phases[n_phases, 0], phases[n_phases, 1] = t, bits
            phases[n_phases, 2 : 2 + n] = x
            phases[n_phases, 2 + n :] = v
            n_phases += 1
        horizon, horizon_ball = t_end - t, -1
        for ball in range(n):
            free = not active[ball] and (ball == n - 1 or not active[ball + 1])
            if free and 0.0 < v[ball] < horizon:
                horizon, horizon_ball = v[ball], ball  # a free ball's apex is v away
        event, index, tau, x, v = advance_phase(
            t, x, v, active, horizon, horizon_ball, store, masses, zeta, entered_by, carried, pair
        )
        # A state that leaves a grounded cluster of several contacts carries the rounding of its
        # closed form about the static rest (see twoball.exact.run).
        grounded_top = 0
        while active[0] and grounded_top + 1 < n and active[grounded_top + 1]:
            grounded_top += 1
        if grounded_top > 0:
            cid = _cluster_id(0, grounded_top, True, n)
            offset = np.abs(store.eta_rest[cid, : grounded_top + 1]).sum()
            carried = max(carried, ROUNDING * store.noise[cid] * offset)
        entered_by = index if event == EV_SWITCH else -1
        t += tau
        if event == EV_SWITCH:
            if active[index]:
                contacts = exact._room_for_one(contacts, n_contacts)
                contacts[n_contacts, 0], contacts[n_contacts, 1] = index, opened[index]
                contacts[n_contacts, 2] = t
                n_contacts += 1
            else:
                opened[index] = t
                if top_apexes == 0:
                    first[index] += 1
            active[index] = not active[index]
        elif event == EV_APEX:
            v[index] = 0.0
            apexes = exact._room_for_one(apexes, n_apex)
            apexes[n_apex, 0], apexes[n_apex, 1], apexes[n_apex, 2] = index, t, x[index]
            n_apex += 1
            if index == n - 1:
                top_apexes += 1
                if top_apexes == apexes_wanted:
                    status = STATUS_DONE
                    break
        elif event == EV_TIME:
            status = STATUS_DONE
            break
        elif event == EV_REST:
            status = STATUS_REST
            break
        elif event == EV_STEPS:
            status = STATUS_PHASES
            break
        else:
            status = STATUS_STUCK
            break
    for c in range(n):  # contacts still open at the end end there
        if active[c]:
            contacts = exact._room_for_one(contacts, n_contacts)
            contacts[n_contacts, 0], contacts[n_contacts, 1], contacts[n_contacts, 2] = (
                c,
                opened[c],
                t,
            )
            n_contacts += 1
    return StackRun(
        status, t, apexes[:n_apex].copy(), contacts[:n_contacts].copy(), first, phases[:n_phases]
    )


@njit
def sample(phases, times, masses, zeta):
    """Exact heights, velocities and contact forces at the given times from the recorded
    phases: arrays (len(times), N) each."""
    n = masses.size
    store = new_clusters(n)
    heights = np.empty((times.size, n))
    speeds = np.empty((times.size, n))
    forces = np.zeros((times.size, n))
    x = np.empty(n)
    v = np.empty(n)
    a = np.empty(n)
    shape_z = np.zeros((n, 2 * n))
    shape_w = np.zeros((n, 2 * n))
    mode_z = np.zeros((n, 2 * n))
    mode_w = np.zeros((n, 2 * n))
    active = np.zeros(n, dtype=np.bool_)
    current = -1
    phase = _phase(active, phases[0, 2 : 2 + n], phases[0, 2 + n :], store, masses, zeta)
    for s in range(times.size):
        index = max(np.searchsorted(phases[:, 0], times[s], side="right") - 1, 0)
        bits = int(phases[index, 1])
        for c in range(n):
            active[c] = (bits >> c) & 1 == 1
        if index != current:
            phase = _phase(
                active, phases[index, 2 : 2 + n], phases[index, 2 + n :], store, masses, zeta
            )
            current = index
        tau = times[s] - phases[index, 0]
        _evaluate(tau, phase, store, n, x, v, a, shape_z, shape_w, mode_z, mode_w)
        heights[s] = x
        speeds[s] = v
        for c in range(n):
            if active[c]:
                eta = x[c] - (x[c - 1] if c >= 1 else 0.0)
                deta = v[c] - (v[c - 1] if c >= 1 else 0.0)
                forces[s, c] = max(-(eta + 2.0 * zeta[c] * deta), 0.0)
    return heights, speeds, forces


# --- the public layer: validation, simulate_stack, the ICM chain -------------------------------

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


def _values(name: str, declared: str, values: object, count: int, what: str) -> list[float]:
    """One value or ``count`` values of a declared parameter, checked."""
    try:
        items = list(np.ravel(np.asarray(values, dtype=object)))
    except (TypeError, ValueError):
        items = [values]
    if len(items) == 1:
        return [_checked(declared, name, items[0])] * count
    if len(items) != count:
        if count == 1:
            raise ParameterError(
                f"{name} must hold one value ({what}, and there is one); got {len(items)}"
            )
        raise ParameterError(f"{name} must hold one value or {count} ({what}); got {len(items)}")
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
    or N (the floor's, then each pair's); ``tau_ratios`` one gap or N - 1 (each a ``tau_ratio``,
    the delay td_i over the floor contact time); ``force`` the contact law, which sets the
    smallest gap (:data:`TOUCHING_LIMIT_BALLS`) and, for Hertz, the smallest eps. Raises
    ``ParameterError`` (a ``ValueError``) naming the parameter and its allowed range.
    """
    if force not in FORCES:
        raise ParameterError(f"force must be one of {', '.join(FORCES)}; got {force!r}")
    try:
        ratios = list(np.ravel(np.asarray(mass_ratios, dtype=object)))
    except (TypeError, ValueError):
        ratios = [mass_ratios]
    if not 1 <= len(ratios) <= MAX_BALLS - 1:
        raise ParameterError(
            f"mass_ratios must hold 1 to {MAX_BALLS - 1} values (N = 2 to {MAX_BALLS} balls); "
            f"got {len(ratios)}"
        )
    ratios = [_checked("mu", f"mass_ratios[{i}]", value) for i, value in enumerate(ratios)]
    balls = len(ratios) + 1
    restitutions = _values("eps", "eps", eps, balls, "the floor's, then each pair's")
    gaps = _values("tau_ratios", "tau_ratio", tau_ratios, balls - 1, "one per pair")
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
    from twoball import hertz

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
    if force == "hertz":
        from twoball import hertz

        tau_f = hertz.floor_contact_time(restitutions[0], height)
        x_start = release_heights(height, gaps, tau_f)
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
    return (math.sqrt(height) + delays / math.sqrt(2.0)) ** 2


@dataclass(frozen=True)
class StackContact:
    """One interval during which contact ``contact`` pushes (0: the floor, i: ball i on i-1)."""

    contact: int
    start: float
    end: float


@dataclass
class StackTrajectory:
    """Sampled heights, velocities (len(t), N) and contact forces (len(t), N; floor first)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    f: np.ndarray


@dataclass
class StackResult:
    """The outcome of one stack drop: the top ball's apexes ``h1``, ``h2`` (as ``simulate``'s),
    every ball's apexes in free flight, every contact interval, how the run ended."""

    stack: Stack
    force: str
    apexes: list[list[tuple[float, float]]]  # per ball: (t, height) of each apex
    contacts: list[StackContact]
    contacts_first: list[int]  # intervals of each contact that start before h1
    end_time: float
    status: Status
    trajectory: StackTrajectory | None = field(default=None, repr=False)

    @property
    def success(self) -> bool:
        """True when the run reached what was asked or the stack came to rest."""
        return self.status.success

    @property
    def h1(self) -> float | None:
        """The top ball's first apex in free flight (None without one)."""
        top = self.apexes[-1]
        return top[0][1] if top else None

    @property
    def h2(self) -> float | None:
        """The top ball's second apex (None without one)."""
        top = self.apexes[-1]
        return top[1][1] if len(top) > 1 else None

    @property
    def h_icm(self) -> float:
        """The ICM chain's height for the top ball (:func:`icm_chain`)."""
        return icm_chain(self.stack)[-1]

    def summary(self) -> dict[str, object]:
        """The observables as plain values (JSON-ready: None where absent)."""
        stack = self.stack
        return {
            "balls": stack.balls,
            "mass_ratios": list(stack.mass_ratios),
            "eps": list(stack.eps),
            "tau_ratios": list(stack.tau_ratios),
            "height": stack.height,
            "force": self.force,
            "h1": self.h1,
            "h2": self.h2,
            "h_icm_chain": self.h_icm,
            "h1_over_icm": None if self.h1 is None else self.h1 / self.h_icm,
            "h1_over_drop": None if self.h1 is None else self.h1 / stack.x_start[-1],
            "h2_over_h1": None if self.h2 is None else self.h2 / self.h1,
            "contacts_first": list(self.contacts_first),
            "first_apexes": [apexes[0][1] if apexes else None for apexes in self.apexes],
            "status": self.status.name,
        }


def simulate_stack(
    mass_ratios: object,
    eps: object,
    tau_ratios: object,
    *,
    height: float = DEFAULT_HEIGHT,
    force: str = "linear",
    until: str | float = "second",
    t_eval: object = None,
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
        One restitution for every contact, or N of them: the floor's, then each pair's.
    tau_ratios : float or sequence of float
        One gap or N - 1: ball i + 1 reaches its touching height td_i = tau_ratio_i * tau_f
        after ball i would, in free fall.
    height : float
        Dimensionless drop height H of ball 0.
    force : "linear" or "hertz"
        The contact force: the linear spring-dashpot, solved exactly, or Hertz's with
        Hunt-Crossley damping (:mod:`twoball.hertz`).
    until : "first", "second" or float
        The top ball's apex to run to, or a dimensionless time.
    t_eval : array_like, optional
        Times at which ``StackResult.trajectory`` samples heights, velocities and forces.
    throw : bool
        A run that fails raises :class:`~twoball.errors.SolverError`; with False the result says
        so (``success``, ``status``).
    method : "compiled" or "DOP853"
        With the Hertz force: the compiled integrator, or scipy's DOP853, kept as a reference
        (:func:`twoball.hertz.simulate`).

    Returns
    -------
    StackResult

    Examples
    --------
    With two balls it is :func:`twoball.simulate`:

    >>> import twoball
    >>> from twoball.stack import simulate_stack
    >>> pair = simulate_stack([0.01], 0.9, 0.01)
    >>> single = twoball.simulate(0.9, 0.01, 0.01)
    >>> bool(abs(pair.h2 - single.h2) < 1e-9 * single.h2), pair.contacts_first[1]
    (True, 4)
    """
    stack = check_stack(mass_ratios, eps, tau_ratios, height=height, force=force)
    apexes_wanted, t_end = stop_rule(until)
    times = None
    if t_eval is not None:
        times = as_times("t_eval", t_eval)
        check_span("t_eval", times, math.inf, False)  # no time before the release
    if force == "hertz":
        from twoball import hertz

        result = hertz.simulate(stack, apexes_wanted, t_end, times, method)
        stack = result.stack  # its gaps are in units of the Hertz floor contact
    else:
        out = run(
            stack.masses,
            stack.zeta,
            stack.x_start,
            apexes_wanted,
            t_end,
            times is not None,
            _store_for(stack),
        )
        apexes: list[list[tuple[float, float]]] = [[] for _ in range(stack.balls)]
        for ball, when, where in out.apexes.tolist():
            apexes[int(ball)].append((when, where))
        trajectory = None
        if times is not None:
            heights, speeds, forces = sample(out.phases, times, stack.masses, stack.zeta)
            trajectory = StackTrajectory(times, heights, speeds, forces)
        result = StackResult(
            stack=stack,
            force=force,
            apexes=apexes,
            # tolist: Python floats at once, not a numpy scalar per value (a third of the
            # three-ball drop's time outside the kernel)
            contacts=[StackContact(int(c), s, e) for c, s, e in out.contacts.tolist()],
            contacts_first=[int(count) for count in out.contacts_first],
            end_time=float(out.end_time),
            status=Status(out.status),
            trajectory=trajectory,
        )
    if times is not None and result.status.success:
        # after the end the closed form (linear) would be extrapolated, or nothing sampled
        # (Hertz); after a proven rest every later state is that rest's
        check_span("t_eval", times, result.end_time, result.status is Status.REST)
    bound = _apex_bound(stack, force)
    top = [h for _, h in result.apexes[-1]]
    if any(not math.isfinite(h) or h > bound * (1.0 + 1e-9) for h in top):
        result.status = Status.IMPOSSIBLE
    if throw and not result.success:
        message = result.status.message
        if result.status is Status.PHASE_LIMIT:
            message += phase_limit_hint(stack.eps[0])
        raise SolverError(f"the stack run failed on {stack}: {message}", result)
    return result


# The clusters' closed forms of the last few stacks, by masses and damping ratios: a cluster is
# built on first use (an eigenvector form: about 0.1 ms for all of three balls', 1.7 ms for
# eight balls'), so drops of the same balls from other heights or gaps (a sweep, the app) reuse
# them. The kernel holds the GIL, so one store is never filled by two runs at once.
_STORES: dict[bytes, Clusters] = {}
STORES_KEPT = 8


def _store_for(stack: Stack) -> Clusters:
    """The cluster store for this stack's balls, the most recently used kept last."""
    key = stack.masses.tobytes() + stack.zeta.tobytes()
    store = _STORES.pop(key, None)
    if store is None:
        store = new_clusters(stack.balls)
    _STORES[key] = store
    while len(_STORES) > STORES_KEPT:
        del _STORES[next(iter(_STORES))]
    return store


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

    Ball 0 hits the floor at sqrt(2H) and leaves with eps_0 times it; then ball i, still falling
    at sqrt(2H), meets ball i - 1 going up, with restitution eps_i. Returns each ball's rebound
    height above its contact point (v^2/2). For an elastic three-ball stack with vanishing mass
    ratios the top ball leaves at 7 sqrt(2H): 49 times as high.
    """
    impact = math.sqrt(2.0 * stack.height)
    up = stack.eps[0] * impact
    heights = [up * up / 2.0]
    for i in range(1, stack.balls):
        below, mass = stack.masses[i - 1], stack.masses[i]
        restitution = stack.eps[i]
        # momentum and restitution: (u - u_below) = -eps (v - v_below), with v = -impact
        up = (below * up - mass * impact + restitution * below * (up + impact)) / (below + mass)
        heights.append(up * up / 2.0)
    return heights
